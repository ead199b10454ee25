#include "chasles/server/benchmark.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <ctime>
#include <deque>
#include <memory>
#include <optional>
#include <sstream>
#include <thread>
#include <utility>
#include <vector>

#include <ompl/base/SpaceInformation.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/PathGeometric.h>

#include <grpcpp/impl/codegen/proto_utils.h>

#include "chasles/optimizers/shortcut.h"
#include "chasles/robot/error.h"
#include "chasles/server/benchmark_report.h"
#include "chasles/server/convert.h"
#include "chasles/server/groups.h"
#include "chasles/server/heap_tracking.h"
#include "chasles/server/status.h"

namespace chasles {
namespace {

using Clock = std::chrono::steady_clock;

double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

/// OMPL's smoothness (PathGeometric::smoothness) of a joint path, in a Euclidean joint space.
double OmplSmoothness(const JointPath& path) {
  if (path.size() < 3) return 0.0;
  const unsigned int n = static_cast<unsigned int>(path.front().size());
  auto space = std::make_shared<ompl::base::RealVectorStateSpace>(n);
  auto si = std::make_shared<ompl::base::SpaceInformation>(space);
  ompl::geometric::PathGeometric geometric(si);
  ompl::base::State* state = si->allocState();
  for (const Eigen::VectorXd& q : path) {
    auto* values = state->as<ompl::base::RealVectorStateSpace::StateType>()->values;
    for (unsigned int i = 0; i < n; ++i) values[i] = q[i];
    geometric.append(state);  // copies
  }
  si->freeState(state);
  return geometric.smoothness();
}

std::string Hostname() {
  char name[256] = {0};
  if (gethostname(name, sizeof(name) - 1) != 0) return "unknown";
  return name;
}

std::string LocalDate() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  localtime_r(&now, &tm);
  char buffer[64];
  std::strftime(buffer, sizeof(buffer), "%Y-%m-%dT%H:%M:%S", &tm);
  return buffer;
}

std::string ParameterText(const v1::ParameterValue& value) {
  switch (value.value_case()) {
    case v1::ParameterValue::kDoubleValue: return FormatNumber(value.double_value());
    case v1::ParameterValue::kIntValue: return std::to_string(value.int_value());
    case v1::ParameterValue::kBoolValue: return value.bool_value() ? "true" : "false";
    default: return "unset";
  }
}

}  // namespace

/// One Benchmark call: the reactor, its runs and its write queue.
class BenchmarkCall final : public grpc::ServerWriteReactor<grpc::ByteBuffer> {
 public:
  BenchmarkCall(const BenchmarkServices& services, BenchmarkRegistry* registry, const v1::BenchmarkRequest* request,
                std::string request_id, Clock::time_point deadline)
      : services_(services),
        registry_(registry),
        request_(*request),
        request_id_(std::move(request_id)),
        deadline_(deadline),
        shared_(deadline + std::chrono::hours(1), deadline),
        started_(Clock::now()) {}

  /// Queues the preparation on the pool.
  void Begin() {
    if (!services_.pool->Submit([this] { Prepare(); }, services_.ticket)) {
      Finish(grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED, "the server's work queue is full; retry later"));
    }
  }

  /// StopBenchmark: drop the runs in flight, start no more, answer the summary.
  void Stop() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_) return;
    stopping_ = true;
    stopped_by_request_ = true;
    shared_.Cancel();
  }

  void OnCancel() override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      client_gone_ = true;
      stopping_ = true;
      queue_.erase(queue_.begin() + (writing_ ? 1 : 0), queue_.end());
    }
    shared_.Cancel();
    ticker_wake_.notify_all();
    registry_->Remove(request_id_, this);  // the id is free at once, while the runs wind down
  }

  void OnWriteDone(bool ok) override {
    const grpc::ByteBuffer* next = nullptr;
    bool finish = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      writing_ = false;
      queue_.pop_front();
      if (!ok) {
        client_gone_ = true;
        stopping_ = true;
        queue_.clear();
        shared_.Cancel();
      }
      if (!queue_.empty() && !client_gone_) {
        writing_ = true;
        next = &queue_.front();
      } else if (final_status_ && !finish_called_) {
        finish_called_ = true;
        finish = true;
      }
    }
    if (next) StartWrite(next);
    if (finish) Finish(*final_status_);  // last access to this call
  }

  void OnDone() override { delete this; }

 private:
  // --- preparation -------------------------------------------------------------------------

  void Prepare() {
    try {
      BuildQueries();
    } catch (...) {
      const grpc::Status status = StatusFromException(std::current_exception());
      Log("benchmark request=" + request_id_ + " status=" + std::to_string(status.error_code()) +
          " message=" + status.error_message());
      Finish(status);
      return;
    }
    if (!registry_->Add(request_id_, this)) {
      Finish(grpc::Status(grpc::StatusCode::ALREADY_EXISTS,
                          "request_id = '" + request_id_ + "' names a benchmark that is running already; choose another id"));
      return;
    }
    registered_ = true;
    Log("benchmark request=" + request_id_ + " problems=" + std::to_string(problem_names_.size()) +
        " configs=" + std::to_string(config_names_.size()) + " runs=" + std::to_string(runs_) +
        " total=" + std::to_string(total_) + " parallelism=" + std::to_string(parallelism_) + " started");
    std::vector<std::pair<std::uint32_t, std::uint32_t>> launch;  // (index, slot)
    const grpc::ByteBuffer* write = nullptr;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      write = Enqueue(ProgressMessage());
      if (!stopping_) {
        while (next_ < total_ && running_ < parallelism_) {
          launch.emplace_back(next_++, running_);
          ++running_;
        }
      }
    }
    Write(write);
    ticker_ = std::thread([this] { Tick(); });
    if (launch.empty()) {
      Complete();
      return;
    }
    for (const auto& [index, slot] : launch) Submit(index, slot);
  }

  /// Every (problem, configuration) query, validated; names, settings and limits.
  void BuildQueries() {
    const v1::BenchmarkRequest& r = request_;
    if (r.problems_size() < 1 || r.problems_size() > 256) {
      ThrowInvalid("problems has " + std::to_string(r.problems_size()) + " entries; must have 1 to 256");
    }
    if (r.configs_size() < 1 || r.configs_size() > 64) {
      ThrowInvalid("configs has " + std::to_string(r.configs_size()) + " entries; must have 1 to 64");
    }
    runs_ = r.runs() == 0 ? 10 : r.runs();
    if (runs_ > 10000) ThrowInvalid("runs = " + std::to_string(r.runs()) + " must be at most 10000");
    run_budget_ = r.run_budget() == 0.0 ? 5.0 : r.run_budget();
    if (!(run_budget_ > 0.0 && run_budget_ <= 600.0)) {
      ThrowInvalid("run_budget = " + FormatNumber(r.run_budget()) + " must be in (0, 600] s (0 = 5)");
    }
    trajectories_ = r.trajectories();
    progress_interval_ = r.progress_interval() == 0.0 ? 0.5 : r.progress_interval();
    if (!(progress_interval_ > 0.0 && progress_interval_ <= 3600.0)) {
      ThrowInvalid("progress_interval = " + FormatNumber(r.progress_interval()) + " must be in (0, 3600] s (0 = 0.5)");
    }
    seed_ = r.seed() == 0 ? 1 : r.seed();
    const std::uint32_t threads = static_cast<std::uint32_t>(services_.pool->num_threads());
    parallelism_ = r.parallelism() == 0 ? threads : std::min(r.parallelism(), threads);
    experiment_ = r.experiment().empty() ? "chasles" : r.experiment();

    std::map<std::string, int> seen;
    for (int p = 0; p < r.problems_size(); ++p) {
      std::string name = r.problems(p).name().empty() ? "problem" + std::to_string(p) : r.problems(p).name();
      if (!seen.emplace(name, p).second) {
        ThrowInvalid("problems[" + std::to_string(p) + "].name = '" + name + "' repeats problems[" +
                     std::to_string(seen[name]) + "].name; names must be unique");
      }
      problem_names_.push_back(name);
    }
    seen.clear();
    std::map<std::string, int> planner_uses;
    for (int c = 0; c < r.configs_size(); ++c) {
      const v1::BenchmarkConfig& config = r.configs(c);
      const std::string planner = config.planner().planner_id().empty() ? "rrt_connect" : config.planner().planner_id();
      std::string name = config.name();
      if (name.empty()) {
        const int use = planner_uses[planner]++;
        name = use == 0 ? planner : planner + "#" + std::to_string(c);
      }
      if (!seen.emplace(name, c).second) {
        ThrowInvalid("configs[" + std::to_string(c) + "].name = '" + name + "' repeats configs[" +
                     std::to_string(seen[name]) + "].name; names must be unique");
      }
      config_names_.push_back(name);
      std::vector<std::string> settings = {"planner = " + planner};
      std::map<std::string, std::string> sorted;
      for (const auto& [key, value] : config.planner().parameters()) sorted[key] = ParameterText(value);
      for (const auto& [key, value] : sorted) settings.push_back(key + " = " + value);
      if (config.has_trajectory()) {
        settings.push_back("post_processing = " +
                           v1::TrajectoryOptions::PostProcessing_Name(config.trajectory().post_processing()));
      }
      config_settings_.push_back(std::move(settings));
    }

    const std::size_t P = problem_names_.size(), C = config_names_.size();
    queries_.resize(P * C);
    for (std::size_t p = 0; p < P; ++p) {
      const std::string prefix = "problems[" + std::to_string(p) + "].request.";
      v1::PlanRequest problem = r.problems(static_cast<int>(p)).request();
      if (problem.has_workcell()) ThrowInvalid(prefix + "workcell is set; benchmarks plan without workcells");
      StoredRobot robot;
      StoredScene scene;
      double padding = 0.0;
      std::vector<std::string> group_warnings;
      try {
        robot = RobotOfRequest(*services_.store, problem, prefix + "robot");
        // A planning group: the robot held outside it where the start puts it, start and goal
        // narrowed to its joints (as Plan does); clamped values are reported in the setup.
        if (!problem.group().empty()) robot = NarrowToGroup(robot, &problem, &group_warnings, prefix);
        scene = SceneOfRequest(*services_.store, problem, prefix + "scene");
        padding = PaddingFromProto(problem.padding(), prefix + "padding");
      } catch (const Error& e) {
        throw Error(e.code(), "problem '" + problem_names_[p] + "': " + e.what());
      }
      const std::shared_ptr<const CollisionChecker> checker = services_.store->Checker(robot, scene, padding);
      for (std::size_t c = 0; c < C; ++c) {
        const v1::BenchmarkConfig& config = r.configs(static_cast<int>(c));
        RequestSettings settings;
        try {
          // Validated here (PlanQueryFromProto), so every error comes before any run starts.
          queries_[p * C + c] = PlanQueryFromProto(BenchmarkRunRequest(problem, config, run_budget_, seed_), checker,
                                                   *services_.registry, &settings);
        } catch (const Error& e) {
          // Name the field where the user wrote it: the configuration's planner/trajectory, or the problem.
          const std::string message = e.what();
          const bool from_config = message.rfind("planner", 0) == 0 ||
                                   (config.has_trajectory() && message.rfind("trajectory", 0) == 0);
          if (from_config) {
            throw Error(e.code(), "configs[" + std::to_string(c) + "]." + message + " (configuration '" +
                                      config_names_[c] + "', problem '" + problem_names_[p] + "')");
          }
          throw Error(e.code(), prefix + message + " (problem '" + problem_names_[p] + "')");
        }
      }
      std::ostringstream setup;
      setup << "problem " << problem_names_[p] << ": robot " << robot.model->name() << " (" << robot.id.substr(0, 12)
            << "), scene " << scene.id.substr(0, 12) << ", " << robot.model->num_dofs() << " joints";
      if (!problem.group().empty()) setup << " of group " << problem.group() << " (the others held at the start)";
      for (const std::string& warning : group_warnings) setup << "\nwarning: " << warning;
      setup << "\nstart";
      const PlanQuery& q = queries_[p * C];
      for (int i = 0; i < q.start.size(); ++i) setup << " " << FormatNumber(q.start[i]);
      if (q.pose_goal) {
        setup << "\npose goal for link " << robot.model->links()[q.pose_goal->link].name;
      } else {
        setup << "\ngoal";
        for (int i = 0; i < q.goal.size(); ++i) setup << " " << FormatNumber(q.goal[i]);
      }
      setups_.push_back(setup.str());
    }
    total_ = static_cast<std::uint32_t>(P * C * runs_);
  }

  // --- runs ----------------------------------------------------------------------------------

  void Submit(std::uint32_t index, std::uint32_t slot) {
    if (services_.pool->Submit([this, index, slot] { Run(index, slot); }, services_.ticket)) return;
    bool complete = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      --running_;
      if (!queue_full_) Log("benchmark request=" + request_id_ + " the work queue is full: stopping early");
      queue_full_ = true;
      stopping_ = true;
      complete = running_ == 0;
    }
    if (complete) Complete();
  }

  void Run(std::uint32_t index, std::uint32_t slot) {
    const std::size_t P = problem_names_.size(), C = config_names_.size();
    const std::uint32_t run = index / static_cast<std::uint32_t>(P * C);
    const std::uint32_t problem = (index / static_cast<std::uint32_t>(C)) % static_cast<std::uint32_t>(P);
    const std::uint32_t config = index % static_cast<std::uint32_t>(C);

    v1::BenchmarkRun result;
    bool keep = false;
    bool deadline = false;
    {
      bool skip;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        skip = stopping_;
      }
      if (!skip) {
        PlanQuery query = queries_[problem * C + config];
        query.seed = seed_ + run;
        const Termination termination = shared_.WithBudget(std::chrono::duration<double>(run_budget_));
        const Clock::time_point start = Clock::now();
        HeapScope heap;
        PlanOutcome outcome;
        std::string error;
        try {
          outcome = services_.pipeline->Plan(query, termination);
        } catch (const std::exception& e) {
          error = e.what();
        }
        const double total = Seconds(Clock::now() - start);
        deadline = outcome.code == PlanOutcomeCode::kDeadlineExceeded ||
                   termination.Reason() == StopReason::kDeadline;
        keep = outcome.code != PlanOutcomeCode::kCancelled && !deadline;
        result.set_problem(problem);
        result.set_config(config);
        result.set_run(run);
        result.set_seed(query.seed);
        result.set_worker(slot);
        if (!error.empty()) {
          result.set_outcome(v1::PLAN_OUTCOME_UNSPECIFIED);
          result.set_message("the run failed: " + error);
        } else {
          result.set_outcome(OutcomeToProto(outcome.code));
          result.set_message(outcome.message);
        }
        const bool solved = error.empty() && outcome.code == PlanOutcomeCode::kSuccess;
        result.set_solved(solved);
        result.set_approximate(outcome.code == PlanOutcomeCode::kApproximateOnly);
        result.set_plan_time(outcome.seconds.validate + outcome.seconds.plan);
        result.set_post_time(outcome.seconds.shortcut + outcome.seconds.parameterize + outcome.seconds.optimize +
                             outcome.seconds.verify);
        result.set_total_time(total);
        result.set_raw_path_length(outcome.raw_path.empty() ? 0.0 : PathLength(outcome.raw_path));
        result.set_path_length(solved ? PathLength(outcome.path) : 0.0);
        result.set_duration(solved ? outcome.trajectory.duration() : 0.0);
        result.set_smoothness(solved ? OmplSmoothness(outcome.path) : 0.0);
        result.set_jerk_integral(solved ? outcome.quality.jerk_integral : 0.0);
        result.set_min_clearance(solved ? outcome.quality.min_clearance : -1.0);
        result.set_collision_checks(outcome.state_checks);
        result.set_graph_states(outcome.graph_states);
        result.set_peak_memory(heap.peak_bytes());
        if (solved && trajectories_) {
          KnotsToProto(outcome.trajectory, query.checker->robot().dof_names(), result.mutable_knots());
        }
      }
    }

    std::uint32_t next = 0;
    bool launch = false, complete = false;
    const grpc::ByteBuffer* write = nullptr;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      --running_;
      if (deadline && !deadline_exceeded_) {
        deadline_exceeded_ = true;
        stopping_ = true;
        shared_.Cancel();
      }
      if (keep && !stopping_) {
        ++done_;
        finished_.push_back(result);
        v1::BenchmarkResponse message = ProgressMessage();
        *message.mutable_run() = result;
        write = Enqueue(std::move(message));
      } else {
        ++dropped_;
      }
      if (!stopping_ && next_ < total_) {
        next = next_++;
        ++running_;
        launch = true;
      } else {
        complete = running_ == 0;
      }
    }
    Write(write);
    if (launch) {
      Submit(next, slot);
    } else if (complete) {
      Complete();
    }
  }

  // --- messages ------------------------------------------------------------------------------

  /// Progress now. Caller holds mutex_.
  v1::BenchmarkResponse ProgressMessage() {
    v1::BenchmarkResponse message;
    v1::BenchmarkProgress* progress = message.mutable_progress();
    const double elapsed = Seconds(Clock::now() - started_);
    progress->set_done(done_);
    progress->set_total(total_);
    progress->set_running(running_);
    progress->set_elapsed(elapsed);
    // Throughput so far times the runs left (the parallelism is in the throughput).
    progress->set_eta(done_ == 0 ? -1.0 : elapsed / done_ * static_cast<double>(total_ - done_));
    return message;
  }

  /// Queues a message. Caller holds mutex_. Returns the message the caller must pass to
  /// StartWrite after releasing mutex_ (the writer was idle), else null. (A write may complete
  /// inline in StartWrite, and OnWriteDone takes mutex_.)
  [[nodiscard]] const grpc::ByteBuffer* Enqueue(const v1::BenchmarkResponse& message) {
    if (client_gone_) return nullptr;
    last_message_ = Clock::now();
    // Serialised here: the stream carries raw bytes (the call's request is parsed by the service).
    grpc::ByteBuffer bytes;
    bool own = false;
    grpc::SerializationTraits<v1::BenchmarkResponse>::Serialize(message, &bytes, &own);
    queue_.push_back(std::move(bytes));
    if (writing_) return nullptr;
    writing_ = true;
    return &queue_.front();
  }

  void Write(const grpc::ByteBuffer* message) {
    if (message) StartWrite(message);
  }

  /// Progress-only messages while runs are long, at most every progress_interval.
  void Tick() {
    std::unique_lock<std::mutex> lock(mutex_);
    const auto interval = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(progress_interval_));
    while (!ticker_stop_) {
      ticker_wake_.wait_until(lock, last_message_ + interval);
      if (ticker_stop_) break;
      if (Clock::now() - last_message_ >= interval && !client_gone_) {
        const grpc::ByteBuffer* write = Enqueue(ProgressMessage());
        lock.unlock();
        Write(write);
        lock.lock();
      }
    }
  }

  /// Every run has ended: the summary (unless the client is gone), then Finish once it is written.
  void Complete() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ticker_stop_ = true;
    }
    ticker_wake_.notify_all();
    if (ticker_.joinable()) ticker_.join();
    if (registered_) registry_->Remove(request_id_, this);

    grpc::Status status;
    bool finish = false;
    const grpc::ByteBuffer* write = nullptr;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (client_gone_) {
        status = grpc::Status(grpc::StatusCode::CANCELLED, "cancelled by the client");
      } else if (deadline_exceeded_) {
        status = grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED,
                              "the gRPC deadline passed after " + std::to_string(done_) + " of " +
                                  std::to_string(total_) + " runs (every finished run was sent)");
      } else if (queue_full_) {
        status = grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                              "the server's work queue filled after " + std::to_string(done_) + " of " +
                                  std::to_string(total_) + " runs; retry with less parallelism or later");
      }
      if (status.ok()) write = Enqueue(SummaryMessage());
      final_status_ = status;
      if (!writing_ && !finish_called_) {
        finish_called_ = true;
        finish = true;
      }
      Log("benchmark request=" + request_id_ + " finished=" + std::to_string(done_) + "/" + std::to_string(total_) +
          " dropped=" + std::to_string(dropped_) + (stopped_by_request_ ? " stopped" : "") +
          " wall=" + FormatNumber(Seconds(Clock::now() - started_)) + " s status=" + std::to_string(status.error_code()));
    }
    Write(write);
    if (finish) Finish(*final_status_);  // last access to this call
  }

  /// The final message. Caller holds mutex_.
  v1::BenchmarkResponse SummaryMessage() {
    v1::BenchmarkResponse message = ProgressMessage();
    v1::BenchmarkSummary* summary = message.mutable_summary();
    for (const std::string& name : problem_names_) summary->add_problem_names(name);
    for (const std::string& name : config_names_) summary->add_config_names(name);
    for (v1::ConfigSummary& s : SummarizeConfigs(finished_, config_names_)) *summary->add_configs() = std::move(s);
    const double wall = Seconds(Clock::now() - started_);
    OmplLogHeader header;
    header.hostname = Hostname();
    header.date = LocalDate();
    header.run_budget = run_budget_;
    header.seed = seed_;
    header.runs = runs_;
    header.total_seconds = wall;
    for (std::size_t p = 0; p < problem_names_.size(); ++p) {
      header.experiment = experiment_ + "_" + problem_names_[p];
      header.setup = setups_[p];
      v1::ProblemLog* log = summary->add_logs();
      log->set_problem(static_cast<std::uint32_t>(p));
      log->set_name(problem_names_[p]);
      log->set_ompl_log(OmplBenchmarkLog(header, static_cast<std::uint32_t>(p), config_names_, config_settings_, finished_));
    }
    summary->set_runs_finished(done_);
    summary->set_runs_total(total_);
    summary->set_stopped(stopped_by_request_);
    summary->set_wall_time(wall);
    summary->set_parallelism(parallelism_);
    summary->set_request_id(request_id_);
    return message;
  }

  void Log(const std::string& line) const {
    if (services_.log) services_.log(line);
  }

  const BenchmarkServices services_;
  BenchmarkRegistry* const registry_;
  const v1::BenchmarkRequest request_;  // a copy: runs read it after the call's own request may be gone
  const std::string request_id_;
  const Clock::time_point deadline_;
  const Termination shared_;  // cancelled by Stop, client cancel or the deadline; runs take a budgeted share
  const Clock::time_point started_;

  // Fixed after Prepare().
  std::vector<std::string> problem_names_, config_names_, setups_;
  std::vector<std::vector<std::string>> config_settings_;
  std::vector<PlanQuery> queries_;  // problem-major: [p * C + c]
  std::uint32_t runs_ = 0, total_ = 0, parallelism_ = 1;
  double run_budget_ = 5.0, progress_interval_ = 0.5;
  bool trajectories_ = false;  ///< each solved run's knots in its BenchmarkRun
  std::uint64_t seed_ = 1;
  std::string experiment_;
  bool registered_ = false;

  std::mutex mutex_;
  std::condition_variable ticker_wake_;
  std::thread ticker_;
  bool ticker_stop_ = false;
  std::uint32_t next_ = 0, running_ = 0, done_ = 0, dropped_ = 0;
  std::vector<v1::BenchmarkRun> finished_;
  bool stopping_ = false, stopped_by_request_ = false, client_gone_ = false, deadline_exceeded_ = false,
       queue_full_ = false;
  std::deque<grpc::ByteBuffer> queue_;  // serialised messages; front is being written when writing_
  bool writing_ = false;
  Clock::time_point last_message_ = Clock::now();
  std::optional<grpc::Status> final_status_;
  bool finish_called_ = false;
};

v1::PlanRequest BenchmarkRunRequest(const v1::PlanRequest& problem, const v1::BenchmarkConfig& config,
                                    double run_budget, std::uint64_t seed) {
  v1::PlanRequest request = problem;
  *request.mutable_planner() = config.planner();
  if (config.has_trajectory()) *request.mutable_trajectory() = config.trajectory();
  request.set_time_budget(run_budget);
  request.set_seed(seed);
  return request;
}

bool BenchmarkRegistry::Add(const std::string& id, BenchmarkCall* call) {
  std::lock_guard<std::mutex> lock(mutex_);
  return calls_.emplace(id, call).second;
}

void BenchmarkRegistry::Remove(const std::string& id, const BenchmarkCall* call) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = calls_.find(id);
  if (it != calls_.end() && it->second == call) calls_.erase(it);
}

bool BenchmarkRegistry::Stop(const std::string& id) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = calls_.find(id);
  if (it == calls_.end()) return false;
  it->second->Stop();
  return true;
}

grpc::ServerWriteReactor<grpc::ByteBuffer>* StartBenchmark(const BenchmarkServices& services,
                                                                 BenchmarkRegistry* registry,
                                                                 const v1::BenchmarkRequest* request,
                                                                 const std::string& request_id,
                                                                 std::chrono::steady_clock::time_point deadline) {
  auto* call = new BenchmarkCall(services, registry, request, request_id, deadline);
  call->Begin();
  return call;
}

}  // namespace chasles
