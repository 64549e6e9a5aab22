// `skytrace sweep SWEEP.yaml --out DIR`: one run of a base scenario per point of a parameter sweep,
// on a process pool here (--local -j N) or as a Slurm array job (--slurm); then the manifest and
// the merged table of summaries (docs/sweeps.md). Every point, wherever it runs, is run by the same
// worker (`--run-points` or `--task-file` with `--task`), so its outputs do not depend on where.
#include <fcntl.h>
#include <fmt/format.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>

#include "commands.hpp"
#include "skytrace/core/cancellation.hpp"
#include "skytrace/core/output_file.hpp"
#include "skytrace/core/text_file.hpp"
#include "skytrace/sim/run.hpp"
#include "skytrace/sim/scenario.hpp"
#include "skytrace/sim/sweep.hpp"

extern char** environ;

namespace skytrace::cli {
namespace {

struct SweepArgs {
  std::string sweep_file;
  std::string out_dir;
  bool local = false;
  int jobs = 0;  // local processes (default: hardware threads / threads per run)
  bool slurm = false;
  std::string partition, time_limit, memory;
  int chunk = 0;         // points per array task (default: so that the array has at most 1000 tasks)
  int max_parallel = 0;  // array throttle, %N
  std::vector<std::string> sbatch_args;
  bool no_wait = false;
  double poll_s = 5.0;
  bool gather = false;
  bool plan_only = false;
  int threads_per_run = 1;
  bool no_truth = false;
  std::vector<std::string> overrides;  // --set, after the sweep file's `set:`
  // The worker (hidden): runs points and records them.
  std::string run_points;
  std::string task_file;
  int task = -1;
};

using Clock = std::chrono::steady_clock;

std::string host_name() {
  char name[256] = {};
  if (gethostname(name, sizeof(name) - 1) != 0) return "";
  return name;
}

std::string shell_quote(const std::string& text) {
  std::string out = "'";
  for (const char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::filesystem::path self_executable() {
  std::error_code ec;
  auto path = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path("skytrace") : path;
}

// --- the worker --------------------------------------------------------------------------------

// Runs one point into runs/ID and records what became of it. Returns the exit code of its run.
int run_point(const sim::SweepPlan& plan, const sim::SweepLayout& layout, std::uint64_t index, const SweepArgs& args) {
  sim::PointRecord record;
  record.id = plan.point_id(index);
  record.overrides = plan.overrides(index);
  record.scenario = plan.scenario.string();
  record.host = host_name();
  std::error_code ec;
  std::filesystem::remove(layout.point_record(record.id), ec);  // a point rerun is not done until it ends
  const auto start = Clock::now();
  Status status = Ok{};
  auto scenario = sim::load_scenario(plan.scenario, record.overrides);
  if (!scenario) {
    status = scenario.error();
  } else {
    sim::RunOptions options;
    options.threads = args.threads_per_run;
    options.write_truth = !args.no_truth;
    auto summary = sim::run_scenario(*scenario, layout.point_dir(record.id), options);
    if (!summary) status = summary.error();
  }
  record.wall_time_s = std::chrono::duration<double>(Clock::now() - start).count();
  if (status) {
    record.status = "done";
  } else {
    record.status = "failed";
    record.exit_code = exit_code_for(status.error());
    record.error = status.error().message;
    if (status.error().code == ErrorCode::kCancelled) {
      record.error += " (SIGTERM comes from scancel, a scheduler's time limit, or a stopped sweep)";
    }
    std::cerr << "skytrace sweep: point " << record.id << " failed: " << record.error << "\n";
  }
  if (auto st = sim::write_point_record(layout, record); !st) return report_error(st.error());
  std::cout << fmt::format("skytrace sweep: point {} {} in {:.2f} s\n", record.id, record.status, record.wall_time_s);
  return record.exit_code;
}

Result<std::vector<std::uint64_t>> parse_point_ids(const sim::SweepPlan& plan, const std::string& list) {
  std::vector<std::uint64_t> out;
  std::istringstream in(list);
  std::string id;
  while (in >> id) {
    for (size_t start = 0; start < id.size();) {
      const size_t comma = std::min(id.find(',', start), id.size());
      const std::string one = id.substr(start, comma - start);
      start = comma + 1;
      if (one.empty()) continue;
      const auto index = plan.point_index(one);
      if (!index) {
        return make_error(ErrorCode::kInvalidArgument,
                          fmt::format("point '{}': not a point of {} (p{:0>6} to {})", one, plan.file.string(), 0,
                                      plan.point_id(plan.point_count - 1)));
      }
      out.push_back(*index);
    }
  }
  return out;
}

int run_worker(const sim::SweepPlan& plan, const sim::SweepLayout& layout, const SweepArgs& args) {
  std::string list = args.run_points;
  if (!args.task_file.empty()) {
    std::ifstream in(args.task_file);
    if (!in) return report_error(make_error(ErrorCode::kIo, args.task_file + ": cannot read the task file"));
    std::string line;
    for (int k = 0; k <= args.task && std::getline(in, line);) {
      if (k++ == args.task) list = line;
    }
    if (list.empty()) {
      return report_error(make_error(ErrorCode::kInvalidArgument, fmt::format("{}: no task {}", args.task_file, args.task)));
    }
  }
  auto indices = parse_point_ids(plan, list);
  if (!indices) return report_error(indices.error());
  for (const std::uint64_t index : *indices) {
    const int code = run_point(plan, layout, index, args);
    if (cancellation_requested()) return code;  // stopped: the other points stay pending
  }
  return kExitOk;
}

// --- what to run ---------------------------------------------------------------------------------

std::vector<std::uint64_t> pending_points(const sim::SweepPlan& plan, const sim::SweepLayout& layout) {
  std::vector<std::uint64_t> out;
  const auto records = sim::read_point_records(plan, layout);
  for (std::uint64_t i = 0; i < plan.point_count; ++i) {
    const auto found = records.find(i);
    if (found == records.end() || !sim::point_done(plan, found->second, i)) out.push_back(i);
  }
  return out;
}

std::vector<std::string> worker_arguments(const sim::SweepPlan& plan, const sim::SweepLayout& layout, const SweepArgs& args) {
  std::vector<std::string> argv = {self_executable().string(), "sweep", std::filesystem::absolute(plan.file).string(),
                                   "--out", std::filesystem::absolute(layout.out).string(),
                                   "--threads-per-run", std::to_string(args.threads_per_run)};
  if (args.no_truth) argv.emplace_back("--no-truth");
  for (const auto& o : args.overrides) {
    argv.emplace_back("--set");
    argv.push_back(o);
  }
  return argv;
}

// --- local process pool --------------------------------------------------------------------------

struct LocalResult {
  std::vector<std::pair<std::uint64_t, std::string>> reasons;  // points whose process died without a record
  bool cancelled = false;
};

Result<LocalResult> run_local(const sim::SweepPlan& plan, const sim::SweepLayout& layout, const SweepArgs& args,
                              const std::vector<std::uint64_t>& pending) {
  LocalResult result;
  std::error_code ec;
  std::filesystem::create_directories(layout.logs(), ec);
  if (ec) return make_error(ErrorCode::kOutput, layout.logs().string() + ": cannot create the folder: " + ec.message());
  int jobs = args.jobs;
  if (jobs <= 0) jobs = std::max(1, static_cast<int>(std::thread::hardware_concurrency()) / std::max(1, args.threads_per_run));
  const std::vector<std::string> base_argv = worker_arguments(plan, layout, args);
  std::map<pid_t, std::uint64_t> running;
  size_t next = 0;
  size_t finished = 0;
  auto start_point = [&](std::uint64_t index) -> Status {
    const std::string id = plan.point_id(index);
    const std::string log = (layout.logs() / (id + ".log")).string();
    std::vector<std::string> argv = base_argv;
    argv.emplace_back("--run-points");
    argv.push_back(id);
    std::vector<char*> c_argv;
    for (auto& a : argv) c_argv.push_back(a.data());
    c_argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    pid_t pid = 0;
    const int rc = posix_spawn(&pid, c_argv[0], &actions, nullptr, c_argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (rc != 0) return make_error(ErrorCode::kIo, fmt::format("cannot start {}: {}", c_argv[0], std::strerror(rc)));
    running[pid] = index;
    return Ok{};
  };
  bool stopping = false;
  while (next < pending.size() || !running.empty()) {
    if (cancellation_requested() && !stopping) {
      stopping = true;
      result.cancelled = true;
      for (const auto& [pid, index] : running) kill(pid, SIGTERM);
    }
    while (!stopping && running.size() < static_cast<size_t>(jobs) && next < pending.size()) {
      if (auto st = start_point(pending[next++]); !st) {
        for (const auto& [pid, index] : running) kill(pid, SIGTERM);
        stopping = true;
        while (!running.empty()) {
          int ignored = 0;
          const pid_t pid = waitpid(-1, &ignored, 0);
          if (pid > 0) running.erase(pid);
          else if (errno != EINTR) break;
        }
        return st.error();
      }
    }
    if (running.empty()) break;
    // Polled, so that a signal to this process alone (SIGTERM) stops the points at once.
    int wait_status = 0;
    const pid_t pid = waitpid(-1, &wait_status, WNOHANG);
    if (pid == 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }
    if (pid < 0) {
      if (errno == EINTR) continue;
      break;
    }
    const auto it = running.find(pid);
    if (it == running.end()) continue;
    const std::uint64_t index = it->second;
    running.erase(it);
    ++finished;
    const std::string id = plan.point_id(index);
    if (!sim::read_point_record(layout, id)) {
      const std::string log = (layout.logs() / (id + ".log")).string();
      result.reasons.emplace_back(
          index, WIFSIGNALED(wait_status)
                     ? fmt::format("its process was killed by signal {} before it recorded a result (log {})", WTERMSIG(wait_status), log)
                     : fmt::format("its process ended with exit code {} without recording a result (log {})",
                                   WEXITSTATUS(wait_status), log));
    }
    if (isatty(fileno(stderr)) != 0) {
      std::fprintf(stderr, "\rskytrace sweep: %zu of %zu points run", finished, pending.size());
      if (finished == pending.size()) std::fputc('\n', stderr);
      std::fflush(stderr);
    }
  }
  return result;
}

// --- Slurm ---------------------------------------------------------------------------------------

struct CommandOutput {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

// Runs a command (no shell: the arguments are quoted) and returns its output.
CommandOutput run_command(const std::vector<std::string>& argv) {
  std::string command;
  for (const auto& a : argv) command += (command.empty() ? "" : " ") + shell_quote(a);
  command += " 2>&1";
  CommandOutput out;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return out;
  char buffer[4096];
  size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) out.output.append(buffer, n);
  const int status = pclose(pipe);
  out.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return out;
}

bool on_path(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path != nullptr ? path : "");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (!dir.empty() && access((std::filesystem::path(dir) / program).c_str(), X_OK) == 0) return true;
  }
  return false;
}

std::string trimmed(std::string text) {
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
  size_t start = 0;
  while (start < text.size() && std::isspace(static_cast<unsigned char>(text[start]))) ++start;
  return text.substr(start);
}

// One submission of the sweep: its array job and which points each task runs.
struct Submission {
  std::string job_id;
  std::filesystem::path task_file;
  std::vector<std::vector<std::string>> tasks;
};

std::filesystem::path submissions_file(const sim::SweepLayout& layout) { return layout.slurm() / "submissions.json"; }

std::vector<Submission> read_submissions(const sim::SweepLayout& layout) {
  std::vector<Submission> out;
  std::ifstream in(submissions_file(layout));
  if (!in) return out;
  try {
    for (const auto& j : nlohmann::json::parse(in)) {
      Submission s;
      s.job_id = j.at("job_id").get<std::string>();
      s.task_file = j.at("task_file").get<std::string>();
      std::ifstream tasks(s.task_file);
      std::string line;
      while (std::getline(tasks, line)) {
        std::istringstream ids(line);
        std::vector<std::string> task;
        std::string id;
        while (ids >> id) task.push_back(id);
        s.tasks.push_back(std::move(task));
      }
      out.push_back(std::move(s));
    }
  } catch (const nlohmann::json::exception&) {
    return {};
  }
  return out;
}

// The states of an array job's tasks still known to the controller; nullopt when Slurm cannot be asked.
std::optional<std::vector<std::string>> job_states(const std::string& job_id, std::string* failure) {
  const CommandOutput q = run_command({"squeue", "-h", "-j", job_id, "-o", "%T"});
  if (q.exit_code != 0) {
    // A job the controller has forgotten is over.
    if (q.output.find("Invalid job id") != std::string::npos) return std::vector<std::string>{};
    if (failure != nullptr) *failure = trimmed(q.output);
    return std::nullopt;
  }
  std::vector<std::string> states;
  std::istringstream lines(q.output);
  std::string line;
  while (std::getline(lines, line)) {
    if (!trimmed(line).empty()) states.push_back(trimmed(line));
  }
  return states;
}

// Why a point of a Slurm task left no record: from the task's log.
std::string slurm_reason(const sim::SweepLayout& layout, const Submission& s, size_t task) {
  const auto log = layout.slurm() / "logs" / fmt::format("{}_{}.log", s.job_id, task);
  auto text = read_text_file(log);
  const std::string where = fmt::format("Slurm job {} task {}", s.job_id, task);
  if (!text) return fmt::format("no result: {} wrote no log ({}): it never started, or was cancelled while queued", where, log.string());
  if (text->find("DUE TO TIME LIMIT") != std::string::npos) {
    return fmt::format("killed by Slurm at its time limit ({}, log {}): raise --time", where, log.string());
  }
  if (text->find("oom-kill") != std::string::npos || text->find("Exceeded job memory limit") != std::string::npos ||
      text->find("OUT_OF_MEMORY") != std::string::npos) {
    return fmt::format("killed by Slurm for exceeding its memory limit ({}, log {}): raise --mem", where, log.string());
  }
  if (text->find("CANCELLED") != std::string::npos) {
    return fmt::format("cancelled by Slurm (scancel, preemption or a node failure; {}, log {})", where, log.string());
  }
  return fmt::format("no result: the task ended before the point did ({}, log {})", where, log.string());
}

// Failure reasons for points of the latest submission that left no record, unless its job still runs.
std::vector<std::pair<std::uint64_t, std::string>> slurm_reasons(const sim::SweepPlan& plan, const sim::SweepLayout& layout,
                                                                 bool* still_running) {
  std::vector<std::pair<std::uint64_t, std::string>> reasons;
  const auto submissions = read_submissions(layout);
  if (submissions.empty()) return reasons;
  const Submission& last = submissions.back();
  if (on_path("squeue")) {
    const auto states = job_states(last.job_id, nullptr);
    if (!states || !states->empty()) {
      if (still_running != nullptr) *still_running = true;
      return reasons;  // queued, running, or Slurm unreachable: nothing is known to have failed
    }
  }
  for (size_t task = 0; task < last.tasks.size(); ++task) {
    for (const std::string& id : last.tasks[task]) {
      const auto index = plan.point_index(id);
      if (!index || sim::read_point_record(layout, id)) continue;
      reasons.emplace_back(*index, slurm_reason(layout, last, task));
    }
  }
  return reasons;
}

Result<Submission> submit_slurm(const sim::SweepPlan& plan, const sim::SweepLayout& layout, const SweepArgs& args,
                                const std::vector<std::uint64_t>& pending) {
  if (!on_path("sbatch") || !on_path("squeue")) {
    return make_error(ErrorCode::kNetwork,
                      "--slurm: sbatch and squeue are not on PATH: Slurm's client commands are not installed here "
                      "(Debian: slurm-client), or run from a login node of the cluster");
  }
  const size_t max_tasks = 1000;  // Slurm's default MaxArraySize is 1001 (indices 0-1000)
  size_t chunk = args.chunk > 0 ? static_cast<size_t>(args.chunk) : (pending.size() + max_tasks - 1) / max_tasks;
  chunk = std::max<size_t>(chunk, 1);
  Submission s;
  for (size_t i = 0; i < pending.size(); i += chunk) {
    std::vector<std::string>& task = s.tasks.emplace_back();
    for (size_t k = i; k < std::min(pending.size(), i + chunk); ++k) task.push_back(plan.point_id(pending[k]));
  }
  std::error_code ec;
  std::filesystem::create_directories(layout.slurm() / "logs", ec);
  if (ec) return make_error(ErrorCode::kOutput, layout.slurm().string() + ": cannot create the folder: " + ec.message());
  const auto previous = read_submissions(layout);
  const size_t number = previous.size() + 1;
  s.task_file = std::filesystem::absolute(layout.slurm() / fmt::format("tasks-{}.txt", number));
  std::string tasks_text;
  for (const auto& task : s.tasks) {
    for (size_t k = 0; k < task.size(); ++k) tasks_text += (k > 0 ? " " : "") + task[k];
    tasks_text += "\n";
  }
  if (auto st = write_file_atomically(s.task_file, tasks_text); !st) return st.error();
  // The job script: a user can read it, and submit it again by hand.
  const auto script_path = std::filesystem::absolute(layout.slurm() / fmt::format("submit-{}.sh", number));
  std::string script = "#!/bin/sh\n";
  script += fmt::format("#SBATCH --job-name={}\n", shell_quote("skytrace-" + plan.name));
  script += fmt::format("#SBATCH --array=0-{}{}\n", s.tasks.size() - 1,
                        args.max_parallel > 0 ? "%" + std::to_string(args.max_parallel) : "");
  script += fmt::format("#SBATCH --output={}\n", (std::filesystem::absolute(layout.slurm()) / "logs" / "%A_%a.log").string());
  script += fmt::format("#SBATCH --cpus-per-task={}\n#SBATCH --ntasks=1\n", args.threads_per_run);
  if (!args.partition.empty()) script += fmt::format("#SBATCH --partition={}\n", args.partition);
  if (!args.time_limit.empty()) script += fmt::format("#SBATCH --time={}\n", args.time_limit);
  if (!args.memory.empty()) script += fmt::format("#SBATCH --mem={}\n", args.memory);
  std::string command = "exec";
  for (const auto& a : worker_arguments(plan, layout, args)) command += " " + shell_quote(a);
  command += " --task-file " + shell_quote(s.task_file.string()) + " --task \"$SLURM_ARRAY_TASK_ID\"";
  script += command + "\n";
  if (auto st = write_file_atomically(script_path, script); !st) return st.error();
  std::vector<std::string> sbatch = {"sbatch", "--parsable"};
  sbatch.insert(sbatch.end(), args.sbatch_args.begin(), args.sbatch_args.end());
  sbatch.push_back(script_path.string());
  const CommandOutput submitted = run_command(sbatch);
  if (submitted.exit_code != 0) {
    return make_error(ErrorCode::kNetwork, fmt::format("sbatch refused the sweep's array job (exit code {}): {}{}", submitted.exit_code,
                                                       trimmed(submitted.output),
                                                       submitted.output.find("Unable to contact") != std::string::npos
                                                           ? " (Slurm's controller is not reachable from here)"
                                                           : ""));
  }
  // --parsable prints "JOBID" or "JOBID;CLUSTER", after any warnings.
  std::string last_line;
  std::istringstream lines(submitted.output);
  for (std::string line; std::getline(lines, line);) {
    if (!trimmed(line).empty()) last_line = trimmed(line);
  }
  s.job_id = last_line.substr(0, last_line.find(';'));
  if (s.job_id.empty() || !std::all_of(s.job_id.begin(), s.job_id.end(), [](unsigned char c) { return std::isdigit(c); })) {
    return make_error(ErrorCode::kNetwork, "sbatch answered no job id: " + trimmed(submitted.output));
  }
  nlohmann::json all = nlohmann::json::array();
  for (const auto& p : previous) all.push_back({{"job_id", p.job_id}, {"task_file", p.task_file.string()}});
  all.push_back({{"job_id", s.job_id}, {"task_file", s.task_file.string()}, {"script", script_path.string()},
                 {"points", pending.size()}, {"tasks", s.tasks.size()}});
  if (auto st = write_file_atomically(submissions_file(layout), all.dump(1) + "\n"); !st) return st.error();
  return s;
}

// Waits until the array job has left the queue. Returns false when stopped by a signal.
Result<bool> wait_for_job(const sim::SweepPlan& plan, const sim::SweepLayout& layout, const Submission& s, double poll_s,
                          size_t points) {
  int failures = 0;
  size_t last_done = static_cast<size_t>(-1);
  for (;;) {
    std::string failure;
    const auto states = job_states(s.job_id, &failure);
    if (!states) {
      if (++failures >= 5) {
        return make_error(ErrorCode::kNetwork,
                          fmt::format("lost contact with Slurm while waiting for job {} ({}); the job may still run: "
                                      "`skytrace sweep {} --out {} --gather` collects it later",
                                      s.job_id, failure, plan.file.string(), layout.out.string()));
      }
    } else {
      failures = 0;
      if (states->empty()) return true;
    }
    // Progress: which records exist (reading them is for the manifest at the end).
    size_t done = 0;
    std::error_code ec;
    for (const auto& task : s.tasks) {
      for (const auto& id : task) done += std::filesystem::exists(layout.point_record(id), ec) ? 1 : 0;
    }
    if (done != last_done) {
      std::cerr << fmt::format("skytrace sweep: Slurm job {}: {} of {} points recorded\n", s.job_id, done, points);
      last_done = done;
    }
    for (double waited_s = 0.0; waited_s < poll_s; waited_s += 0.1) {
      if (cancellation_requested()) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
}

// --- the command -----------------------------------------------------------------------------------

int finish(const sim::SweepPlan& plan, const sim::SweepLayout& layout,
           const std::vector<std::pair<std::uint64_t, std::string>>& reasons, Clock::time_point start, bool quiet_pending = false) {
  auto counts = sim::write_sweep_manifest(plan, layout, reasons);
  if (!counts) return report_error(counts.error());
  const double wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  std::cout << fmt::format("skytrace sweep: {} points: {} done, {} failed, {} pending ({:.2f} s)\n", plan.point_count,
                           counts->done, counts->failed, counts->pending, wall_s);
  for (const char* file : {"manifest.json", "manifest.csv", "summaries.csv"}) {
    std::cout << "  wrote " << (layout.out / file).string() << "\n";
  }
  if (counts->failed > 0) {
    std::cerr << fmt::format("skytrace sweep: {} points failed (manifest.csv says why):", counts->failed);
    for (size_t i = 0; i < std::min<size_t>(counts->failed_ids.size(), 10); ++i) std::cerr << " " << counts->failed_ids[i];
    std::cerr << (counts->failed_ids.size() > 10 ? " ..." : "") << "\n";
    std::cerr << "skytrace sweep: the same command runs them again (finished points are kept)\n";
    return kExitSweepFailed;
  }
  if (counts->pending > 0 && !quiet_pending) {
    std::cerr << "skytrace sweep: the same command runs the pending points (finished points are kept)\n";
  }
  return kExitOk;
}

int sweep(const SweepArgs& args) {
  const auto start = Clock::now();
  if (args.local && args.slurm) return report_error(make_error(ErrorCode::kInvalidArgument, "--local and --slurm: choose one back-end"));
  if (args.threads_per_run < 1 || args.threads_per_run > 1024) {
    return report_error(make_error(ErrorCode::kInvalidArgument, "--threads-per-run: expected 1 to 1024"));
  }
  if (args.poll_s <= 0.0 || !std::isfinite(args.poll_s)) {
    return report_error(make_error(ErrorCode::kInvalidArgument, "--poll-s: expected a positive number of seconds"));
  }
  if (args.out_dir.empty()) {
    return report_error(make_error(ErrorCode::kOutput, "the output folder is an empty path (--out names it)"));
  }
  auto plan = sim::load_sweep(args.sweep_file);
  if (!plan) return report_error(plan.error());
  plan->fixed_overrides.insert(plan->fixed_overrides.end(), args.overrides.begin(), args.overrides.end());
  const sim::SweepLayout layout{args.out_dir};
  if (!args.run_points.empty() || !args.task_file.empty()) return run_worker(*plan, layout, args);
  if (std::filesystem::exists(args.out_dir) && !std::filesystem::is_directory(args.out_dir)) {
    return report_error(make_error(ErrorCode::kOutput, args.out_dir + ": is not a folder"));
  }
  std::error_code ec;
  std::filesystem::create_directories(layout.runs(), ec);
  if (ec) return report_error(make_error(ErrorCode::kOutput, layout.runs().string() + ": cannot create the folder: " + ec.message()));
  if (args.gather) {
    bool running = false;
    const auto reasons = slurm_reasons(*plan, layout, &running);
    if (running) std::cerr << "skytrace sweep: the sweep's last Slurm job is still queued or running (or Slurm did not answer)\n";
    return finish(*plan, layout, reasons, start, running);
  }
  if (auto st = sim::check_sweep_against_scenario(*plan); !st) return report_error(st.error());
  const auto pending = pending_points(*plan, layout);
  if (args.plan_only) return finish(*plan, layout, {}, start, true);
  std::cout << fmt::format("skytrace sweep: {} points, {} to run ({} done before)\n", plan->point_count, pending.size(),
                           plan->point_count - pending.size());
  if (pending.empty()) return finish(*plan, layout, {}, start);
  if (!args.slurm) {
    auto local = run_local(*plan, layout, args, pending);
    if (!local) return report_error(local.error());
    const int code = finish(*plan, layout, local->reasons, start);
    if (local->cancelled) return report_error(cancelled_error());
    return code;
  }
  auto submission = submit_slurm(*plan, layout, args, pending);
  if (!submission) return report_error(submission.error());
  std::cout << fmt::format("skytrace sweep: Slurm job {}: {} tasks for {} points (logs in {})\n", submission->job_id,
                           submission->tasks.size(), pending.size(), (layout.slurm() / "logs").string());
  if (args.no_wait) {
    std::cout << fmt::format("skytrace sweep: not waiting; `skytrace sweep {} --out {} --gather` writes the manifest\n",
                             args.sweep_file, args.out_dir);
    return finish(*plan, layout, {}, start, true);
  }
  auto ended = wait_for_job(*plan, layout, *submission, args.poll_s, pending.size());
  if (!ended) return report_error(ended.error());
  if (!*ended) {
    std::cerr << fmt::format("skytrace sweep: stopped waiting; Slurm job {} goes on (`scancel {}` stops it, `--gather` collects it)\n",
                             submission->job_id, submission->job_id);
    finish(*plan, layout, {}, start, true);
    return report_error(cancelled_error());
  }
  return finish(*plan, layout, slurm_reasons(*plan, layout, nullptr), start);
}

}  // namespace

void register_sweep_command(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<SweepArgs>();
  CLI::App* cmd = app.add_subcommand("sweep",
                                     "Run a parameter sweep or Monte Carlo campaign of a scenario, here or on Slurm: "
                                     "one run per point in DIR/runs/ID, manifest.json/.csv and summaries.csv (docs/sweeps.md)");
  cmd->add_option("sweep", args->sweep_file, "Sweep YAML file (base scenario and axes)")->required();
  cmd->add_option("--out", args->out_dir, "Output folder; running again resumes (finished points are kept)")->required();
  cmd->add_flag("--local", args->local, "Run the points on this machine (the default)");
  cmd->add_option("-j,--jobs", args->jobs, "Points run at once with --local (default: hardware threads / --threads-per-run)")
      ->check(CLI::Range(1, 4096));
  cmd->add_flag("--slurm", args->slurm, "Submit the points as a Slurm array job (sbatch), wait for it, gather the manifest");
  cmd->add_option("--partition", args->partition, "Slurm partition");
  cmd->add_option("--time", args->time_limit, "Slurm time limit of one array task, e.g. 30 or 2:00:00");
  cmd->add_option("--mem", args->memory, "Slurm memory of one array task, e.g. 2G");
  cmd->add_option("--chunk", args->chunk, "Points per array task (default: as many as keep the array within 1000 tasks)")
      ->check(CLI::Range(1, 10'000'000));
  cmd->add_option("--max-parallel", args->max_parallel, "Array tasks running at once (sbatch --array=...%N)")
      ->check(CLI::Range(1, 1'000'000));
  cmd->add_option("--sbatch-arg", args->sbatch_args, "Extra sbatch argument (repeatable), e.g. --sbatch-arg=--account=robotics");
  cmd->add_flag("--no-wait", args->no_wait, "With --slurm: submit and return; --gather writes the manifest later");
  cmd->add_option("--poll-s", args->poll_s, "With --slurm: seconds between queue checks (default 5)");
  cmd->add_flag("--gather", args->gather, "Only gather the points' records into the manifest (after --no-wait)");
  cmd->add_flag("--plan", args->plan_only, "Only check the sweep and write the manifest of its points");
  cmd->add_option("--threads-per-run", args->threads_per_run, "Threads of each point's run (default 1)");
  cmd->add_flag("--no-truth", args->no_truth, "The runs write no truth.csv.zst (nor paths.csv.zst)");
  cmd->add_option("--set", args->overrides,
                  "Override a scenario key in every point, KEY.PATH=YAML_VALUE (repeatable; after the sweep file's set:)");
  cmd->add_option("--run-points", args->run_points, "(worker) run these point ids, comma-separated")->group("");
  cmd->add_option("--task-file", args->task_file, "(worker) a submission's task file")->group("");
  cmd->add_option("--task", args->task, "(worker) the line of --task-file to run")->group("");
  cmd->callback([args, &exit_code]() { exit_code = sweep(*args); });
}

}  // namespace skytrace::cli
