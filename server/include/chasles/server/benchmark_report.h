#pragma once
/// \file
/// Benchmark results as reports: per-configuration summaries, OMPL benchmark logs (the text
/// format `ompl_benchmark_statistics` turns into Planner Arena's SQLite database), and CSV.
/// Pure functions of chasles.v1 messages; used by the server (summaries, logs) and the CLI (CSV).

#include <cstdint>
#include <string>
#include <vector>

#include "chasles/v1/chasles.pb.h"

namespace chasles {

/// The p-quantile (p in [0, 1]) of `values` by linear interpolation between order statistics
/// (numpy's default): p = 0.5 is the median. 0 for an empty list.
double Quantile(std::vector<double> values, double p);

/// One summary per configuration (index order) over `runs` (finished runs, any order):
/// success rate, median and 95th-percentile total time, median planning time, and medians of
/// path length, duration, clearance over the solved runs; median peak memory over all.
std::vector<v1::ConfigSummary> SummarizeConfigs(const std::vector<v1::BenchmarkRun>& runs,
                                                const std::vector<std::string>& config_names);

/// What an OMPL benchmark log says about the experiment besides the runs.
struct OmplLogHeader {
  std::string experiment;  ///< one word (spaces become '_')
  std::string hostname;
  std::string date;        ///< e.g. "2026-11-21T10:00:00"
  std::string setup;       ///< free text: the problem (robot, scene, start, goal)
  double run_budget = 0.0;     ///< [s] per run
  std::uint64_t seed = 0;
  std::uint32_t runs = 0;      ///< runs per planner
  double total_seconds = 0.0;  ///< wall time spent collecting the data [s]
};

/// The OMPL log of one problem: one "planner" per configuration with its `settings` lines
/// ("name = value") as common properties and one line per finished run of that configuration
/// on this problem (from `runs`, which may hold other problems' runs too). Run properties:
/// time, solved, approximate solution, correct solution, status (enum of chasles.v1.PlanOutcome),
/// solution length / smoothness / clearance, simplification time, total time, trajectory duration,
/// jerk integral, graph states, collision checks, memory [MB], seed. Values an unsolved run lacks
/// are written as nan, which the converter stores as NULL.
std::string OmplBenchmarkLog(const OmplLogHeader& header, std::uint32_t problem,
                             const std::vector<std::string>& config_names,
                             const std::vector<std::vector<std::string>>& config_settings,
                             const std::vector<v1::BenchmarkRun>& runs);

/// One CSV line per run, with a header line: problem, config, run, seed, outcome, solved,
/// approximate, plan_time, post_time, total_time, path_length, raw_path_length, duration,
/// smoothness, jerk_integral, min_clearance, collision_checks, graph_states, peak_memory, worker.
/// Problem and configuration columns hold names (quoted when they contain ',' or '"').
std::string BenchmarkRunsCsv(const std::vector<v1::BenchmarkRun>& runs, const std::vector<std::string>& problem_names,
                             const std::vector<std::string>& config_names);

}  // namespace chasles
