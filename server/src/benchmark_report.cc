#include "chasles/server/benchmark_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace chasles {
namespace {

/// Ten significant digits (sub-nanosecond for times of seconds); nan/inf as OMPL's converter expects them.
std::string Number(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return "inf";
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.10g", value);
  return buffer;
}

std::string OneWord(std::string text) {
  for (char& c : text) {
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r') c = '_';
  }
  return text.empty() ? "unnamed" : text;
}

std::string CsvField(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  return quoted + "\"";
}

}  // namespace

double Quantile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double position = std::clamp(p, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const std::size_t below = static_cast<std::size_t>(std::floor(position));
  const std::size_t above = std::min(below + 1, values.size() - 1);
  const double fraction = position - static_cast<double>(below);
  return values[below] + fraction * (values[above] - values[below]);
}

std::vector<v1::ConfigSummary> SummarizeConfigs(const std::vector<v1::BenchmarkRun>& runs,
                                                const std::vector<std::string>& config_names) {
  std::vector<v1::ConfigSummary> summaries(config_names.size());
  for (std::size_t c = 0; c < config_names.size(); ++c) {
    v1::ConfigSummary& s = summaries[c];
    s.set_config(static_cast<std::uint32_t>(c));
    s.set_name(config_names[c]);
    std::vector<double> time, plan_time, memory, length, duration, clearance;
    for (const v1::BenchmarkRun& run : runs) {
      if (run.config() != c) continue;
      s.set_runs(s.runs() + 1);
      time.push_back(run.total_time());
      plan_time.push_back(run.plan_time());
      memory.push_back(static_cast<double>(run.peak_memory()));
      if (run.approximate()) s.set_approximate(s.approximate() + 1);
      if (!run.solved()) continue;
      s.set_solved(s.solved() + 1);
      length.push_back(run.path_length());
      duration.push_back(run.duration());
      clearance.push_back(run.min_clearance());
    }
    s.set_success_rate(s.runs() == 0 ? 0.0 : static_cast<double>(s.solved()) / s.runs());
    s.set_median_time(Quantile(time, 0.5));
    s.set_p95_time(Quantile(time, 0.95));
    s.set_median_plan_time(Quantile(plan_time, 0.5));
    s.set_median_length(Quantile(length, 0.5));
    s.set_median_duration(Quantile(duration, 0.5));
    s.set_median_clearance(Quantile(clearance, 0.5));
    s.set_median_peak_memory(Quantile(memory, 0.5));
  }
  return summaries;
}

std::string OmplBenchmarkLog(const OmplLogHeader& header, std::uint32_t problem,
                             const std::vector<std::string>& config_names,
                             const std::vector<std::vector<std::string>>& config_settings,
                             const std::vector<v1::BenchmarkRun>& runs) {
  std::ostringstream out;
  out << "Chasles version " << CHASLES_VERSION << "\n";
  out << "Experiment " << OneWord(header.experiment) << "\n";
  out << "Running on " << OneWord(header.hostname) << "\n";
  out << "Starting at " << header.date << "\n";
  out << "<<<|\n" << header.setup << (header.setup.empty() || header.setup.back() == '\n' ? "" : "\n") << "|>>>\n";
  out << "<<<|\n|>>>\n";  // cpu information: none
  out << header.seed << " is the random seed\n";
  out << Number(header.run_budget) << " seconds per run\n";
  out << "0 MB per run\n";  // no memory limit
  out << header.runs << " runs per planner\n";
  out << Number(header.total_seconds) << " seconds spent to collect the data\n";

  // The status enum: chasles.v1.PlanOutcome, value i described at position i.
  const google::protobuf::EnumDescriptor* outcomes = v1::PlanOutcome_descriptor();
  int max_value = 0;
  for (int i = 0; i < outcomes->value_count(); ++i) max_value = std::max(max_value, outcomes->value(i)->number());
  out << "1 enum type\nstatus";
  for (int v = 0; v <= max_value; ++v) {
    const google::protobuf::EnumValueDescriptor* value = outcomes->FindValueByNumber(v);
    out << "|" << (value ? value->name() : "unused " + std::to_string(v));
  }
  out << "\n";

  static const char* const kProperties[] = {
      "time REAL",           "solved BOOLEAN",          "approximate solution BOOLEAN", "correct solution BOOLEAN",
      "status ENUM",         "solution length REAL",    "solution smoothness REAL",     "solution clearance REAL",
      "simplification time REAL", "total time REAL",    "trajectory duration REAL",     "jerk integral REAL",
      "graph states INTEGER", "collision checks INTEGER", "memory REAL",                "seed INTEGER"};
  const std::size_t num_properties = sizeof(kProperties) / sizeof(kProperties[0]);

  out << config_names.size() << " planners\n";
  for (std::size_t c = 0; c < config_names.size(); ++c) {
    out << OneWord(config_names[c]) << "\n";
    const std::vector<std::string>& settings = c < config_settings.size() ? config_settings[c] : std::vector<std::string>{};
    out << settings.size() << " common properties\n";
    for (const std::string& line : settings) out << line << "\n";
    out << num_properties << " properties for each run\n";
    for (const char* property : kProperties) out << property << "\n";
    std::vector<const v1::BenchmarkRun*> mine;
    for (const v1::BenchmarkRun& run : runs) {
      if (run.problem() == problem && run.config() == c) mine.push_back(&run);
    }
    std::sort(mine.begin(), mine.end(), [](const v1::BenchmarkRun* a, const v1::BenchmarkRun* b) { return a->run() < b->run(); });
    out << mine.size() << " runs\n";
    const double nan = std::nan("");
    for (const v1::BenchmarkRun* run : mine) {
      const bool solved = run->solved();
      const std::string fields[] = {
          Number(run->plan_time()),
          solved ? "1" : "0",
          run->approximate() ? "1" : "0",
          solved ? "1" : "0",
          std::to_string(static_cast<int>(run->outcome())),
          Number(solved ? run->path_length() : nan),
          Number(solved ? run->smoothness() : nan),
          Number(solved ? run->min_clearance() : nan),
          Number(run->post_time()),
          Number(run->total_time()),
          Number(solved ? run->duration() : nan),
          Number(solved ? run->jerk_integral() : nan),
          std::to_string(run->graph_states()),
          std::to_string(run->collision_checks()),
          Number(static_cast<double>(run->peak_memory()) / (1024.0 * 1024.0)),
          std::to_string(run->seed())};
      for (const std::string& field : fields) out << field << "; ";
      out << "\n";
    }
    out << ".\n";
  }
  return out.str();
}

std::string BenchmarkRunsCsv(const std::vector<v1::BenchmarkRun>& runs, const std::vector<std::string>& problem_names,
                             const std::vector<std::string>& config_names) {
  std::ostringstream out;
  out << "problem,config,run,seed,outcome,solved,approximate,plan_time,post_time,total_time,path_length,"
         "raw_path_length,duration,smoothness,jerk_integral,min_clearance,collision_checks,graph_states,"
         "peak_memory,worker\n";
  const auto name = [](const std::vector<std::string>& names, std::uint32_t i) {
    return i < names.size() ? names[i] : std::to_string(i);
  };
  for (const v1::BenchmarkRun& run : runs) {
    out << CsvField(name(problem_names, run.problem())) << "," << CsvField(name(config_names, run.config())) << ","
        << run.run() << "," << run.seed() << "," << v1::PlanOutcome_Name(run.outcome()) << "," << (run.solved() ? 1 : 0)
        << "," << (run.approximate() ? 1 : 0) << "," << Number(run.plan_time()) << "," << Number(run.post_time()) << ","
        << Number(run.total_time()) << "," << Number(run.path_length()) << "," << Number(run.raw_path_length()) << ","
        << Number(run.duration()) << "," << Number(run.smoothness()) << "," << Number(run.jerk_integral()) << ","
        << Number(run.min_clearance()) << "," << run.collision_checks() << "," << run.graph_states() << ","
        << run.peak_memory() << "," << run.worker() << "\n";
  }
  return out.str();
}

}  // namespace chasles
