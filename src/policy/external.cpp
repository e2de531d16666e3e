// external-process policy: JSON lines over a child's stdin/stdout with timeouts
#include "actionshift/policy/external.hpp"
#include "actionshift/policy/line_process.hpp"
#include "sandbox.hpp"

#include "actionshift/core/hash.hpp"
#include "actionshift/core/json_input.hpp"

#include <nlohmann/json.hpp>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <condition_variable>
#include <csignal>
#include <cstring>
#include <exception>
#include <fcntl.h>
#include <functional>
#include <mutex>
#include <poll.h>
#include <stdexcept>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

extern char** environ;

namespace actionshift::policy {

namespace {
// The process groups of the live policy processes, for kill_external_policies() in a signal handler
// (lock-free slots: a handler may not take a lock). A process beyond the slots is still killed by
// its ExternalPolicy, just not from a signal handler.
constexpr std::size_t kTrackedGroups = 1024;
std::atomic<pid_t> g_groups[kTrackedGroups];
std::atomic<bool> g_interrupted{false};
static_assert(std::atomic<pid_t>::is_always_lock_free && std::atomic<bool>::is_always_lock_free);

void track_group(pid_t pgid) {
  for (auto& slot : g_groups) {
    pid_t expected = 0;
    if (slot.compare_exchange_strong(expected, pgid)) return;
  }
}
void untrack_group(pid_t pgid) {
  for (auto& slot : g_groups) {
    pid_t expected = pgid;
    if (slot.compare_exchange_strong(expected, 0)) return;
  }
}

// Linux sends PR_SET_PDEATHSIG when the *thread* that forked the child ends, not the process: policy
// processes are forked by this one thread, which lives as long as the process (it is never joined;
// the object is never destroyed), so a policy started by a short-lived worker thread is not killed
// when that thread ends. All signals are blocked on it: the process's handlers run elsewhere.
class Spawner {
 public:
  static Spawner& instance() {
    static Spawner* const spawner = new Spawner();
    return *spawner;
  }
  // runs fn on the spawner thread and waits for it
  void run(const std::function<void()>& fn) {
    std::lock_guard<std::mutex> one_at_a_time(call_mutex_);
    std::unique_lock<std::mutex> lock(mutex_);
    job_ = &fn;
    error_ = nullptr;
    cv_.notify_all();
    cv_.wait(lock, [this] { return job_ == nullptr; });
    if (error_) std::rethrow_exception(error_);
  }

 private:
  Spawner() {
    std::thread([this] {
      sigset_t all;
      sigfillset(&all);
      pthread_sigmask(SIG_BLOCK, &all, nullptr);
      std::unique_lock<std::mutex> lock(mutex_);
      for (;;) {
        cv_.wait(lock, [this] { return job_ != nullptr; });
        try {
          (*job_)();
        } catch (...) {
          error_ = std::current_exception();
        }
        job_ = nullptr;
        cv_.notify_all();
      }
    }).detach();
  }
  std::mutex call_mutex_, mutex_;
  std::condition_variable cv_;
  const std::function<void()>* job_{nullptr};
  std::exception_ptr error_;
};
}  // namespace

bool is_line_process_group(int pgid) noexcept {
  if (pgid <= 0) return false;
  for (const auto& slot : g_groups)
    if (slot.load() == pgid) return true;
  return false;
}

void interrupt_external_policies() noexcept { g_interrupted.store(true); }
void clear_external_interrupt() noexcept { g_interrupted.store(false); }
bool external_policies_interrupted() noexcept { return g_interrupted.load(); }
void kill_external_policies() noexcept {
  for (auto& slot : g_groups) {
    const pid_t pgid = slot.load();
    if (pgid > 0) kill(-pgid, SIGKILL);
  }
}

struct LineProcess::Impl {
  pid_t pid{-1};
  int to_child{-1};    // child's stdin
  int from_child{-1};  // child's stdout
  std::string buffer;  // bytes read past the last complete line
  bool exited{false};
  int status{0};

  // reap without blocking; true if the child has exited
  bool poll_exit() {
    if (exited) return true;
    if (pid > 0 && waitpid(pid, &status, WNOHANG) == pid) exited = true;
    return exited;
  }
  std::string exit_text() const {
    if (WIFEXITED(status)) return "process exited with status " + std::to_string(WEXITSTATUS(status));
    if (WIFSIGNALED(status)) return "process killed by signal " + std::to_string(WTERMSIG(status));
    return "process ended";
  }
  ~Impl() {
    if (to_child >= 0) close(to_child);
    if (from_child >= 0) close(from_child);
    if (pid <= 0) return;
    // give it up to 2 s to exit after stdin is closed (none after SIGINT/SIGTERM: a policy blocked in
    // a step would not notice), then kill its process group
    for (int i = 0; i < 200 && !g_interrupted.load() && !poll_exit(); ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    kill(-pid, SIGKILL);
    untrack_group(pid);
    if (!exited) waitpid(pid, &status, 0);
  }
};

namespace {
constexpr std::size_t kMaxReplyBytes = std::size_t{1} << 20;

// a reply as JSON, or a discarded value for anything else (too deep, malformed, out-of-range numbers)
nlohmann::json parse_reply(const std::string& reply) {
  try {
    return parse_json_input(reply, "reply");
  } catch (const InputError&) {
    return nlohmann::json(nlohmann::json::value_t::discarded);
  }
}

std::string excerpt(const std::string& s) {
  std::string e = s.size() > 80 ? s.substr(0, 80) + "..." : s;
  for (char& c : e)
    if (c == '\n' || c == '\r') c = ' ';
  return e;
}
}  // namespace

Action parse_step_reply(std::string_view reply) {
  const nlohmann::json j = parse_reply(std::string(reply));
  if (j.is_discarded()) throw std::invalid_argument("not JSON");
  if (!j.is_object() || !j.contains("action")) throw std::invalid_argument("expected {\"action\": [7 numbers]}");
  const nlohmann::json& a = j.at("action");
  if (!a.is_array() || a.size() != static_cast<std::size_t>(kActionDim))
    throw std::invalid_argument("action must be an array of 7 numbers");
  Action out;
  for (int i = 0; i < kActionDim; ++i) {
    const nlohmann::json& v = a.at(static_cast<std::size_t>(i));
    if (!v.is_number()) throw std::invalid_argument("action must be an array of 7 numbers");
    out(i) = v.get<double>();
    if (!std::isfinite(out(i))) throw std::invalid_argument("non-finite action");
  }
  return out;
}

bool is_ready_reply(std::string_view reply) {
  const nlohmann::json j = parse_reply(std::string(reply));
  return !j.is_discarded() && j.is_object() && j.contains("type") && j.at("type") == "ready";
}

ExternalPolicy::ExternalPolicy(std::string command, sim::TaskId task, ExternalOptions options)
    : command_(std::move(command)), task_(task), options_(options) {
  if (command_.empty()) throw std::invalid_argument("external policy: empty command");
  start();
}

ExternalPolicy::ExternalPolicy(std::string command, sim::TaskId task, ExternalOptions options, std::unique_ptr<LineProcess> proc)
    : command_(std::move(command)), task_(task), options_(options), proc_(std::move(proc)) {}

LineProcess::LineProcess(std::string command, std::string role)
    : command_(std::move(command)), role_(std::move(role)), impl_(std::make_unique<Impl>()) {
  if (command_.empty()) throw std::invalid_argument(role_ + ": empty command");
  static std::once_flag ignore_sigpipe;
  std::call_once(ignore_sigpipe, [] { std::signal(SIGPIPE, SIG_IGN); });
  int in_pipe[2], out_pipe[2];
  if (pipe2(in_pipe, O_CLOEXEC) != 0) throw std::runtime_error(role_ + ": pipe failed");
  if (pipe2(out_pipe, O_CLOEXEC) != 0) {
    close(in_pipe[0]);
    close(in_pipe[1]);
    throw std::runtime_error(role_ + ": pipe failed");
  }
  // The group's leader is a small shell that runs the command in the background (its stdin moved
  // to fd 3 and back, as an asynchronous command's stdin would be /dev/null) and waits for it,
  // exiting with its status. On SIGTERM, which is also its parent-death signal, it kills its whole
  // group: a parent-death signal reaches only the leader, and the shell that runs the command does
  // not exec it (Debian's dash forks `python3 policy.py`), so SIGKILL to the leader alone would
  // leave the policy running.
  std::string sh = "sh", dash_c = "-c", name = "actionshift-policy";
  std::string wrapper =
      "trap 'kill -KILL 0' TERM\n"
      "exec 3<&0 0</dev/null\n"
      "/bin/sh -c \"$1\" <&3 3<&- &\n"
      "exec 3<&- 1>/dev/null\n"
      "wait $!\n";
  char* argv[] = {sh.data(), dash_c.data(), wrapper.data(), name.data(), command_.data(), nullptr};
  const pid_t parent = getpid();
  const detail::SandboxPlan sandbox = detail::sandbox_plan_for(role_ + " '" + command_ + "'");
  int rc = 0;
  Spawner::instance().run([&] {
    const pid_t pid = fork();
    if (pid == 0) {
      // the child of a multi-threaded process: async-signal-safe calls only, until execve.
      // Its own process group, so that a kill also reaches whatever the shell started; SIGTERM
      // (the wrapper then kills its group) when the runner dies, even by SIGKILL (Linux: the
      // parent-death signal survives execve).
      setpgid(0, 0);
      prctl(PR_SET_PDEATHSIG, SIGTERM);
      if (getppid() != parent) _exit(127);  // the runner died before the line above
      // the pipes' ends above 2 first, so that neither dup2 overwrites the other (O_CLOEXEC is
      // cleared on the copies 0 and 1)
      const int in = fcntl(in_pipe[0], F_DUPFD_CLOEXEC, 3);
      const int out = fcntl(out_pipe[1], F_DUPFD_CLOEXEC, 3);
      if (in < 0 || out < 0 || dup2(in, STDIN_FILENO) < 0 || dup2(out, STDOUT_FILENO) < 0) _exit(127);
      // no descriptor of the runner's but stdin, stdout and stderr (a results file opened without
      // O_CLOEXEC would otherwise be readable through /proc/self/fd)
      close_range(3, ~0U, 0);
      detail::enter_sandbox_in_child(sandbox);
      sigset_t none;
      sigemptyset(&none);
      sigprocmask(SIG_SETMASK, &none, nullptr);  // the spawner thread blocks every signal
      execve("/bin/sh", argv, environ);
      _exit(127);
    }
    if (pid < 0) {
      rc = errno;
      return;
    }
    setpgid(pid, pid);  // also here: a kill(-pid) right after fork must not miss
    track_group(pid);
    impl_->pid = pid;
  });
  close(in_pipe[0]);
  close(out_pipe[1]);
  impl_->to_child = in_pipe[1];
  impl_->from_child = out_pipe[0];
  // non-blocking on our side: every read and write waits in poll() with the protocol's timeouts
  fcntl(impl_->to_child, F_SETFL, fcntl(impl_->to_child, F_GETFL) | O_NONBLOCK);
  fcntl(impl_->from_child, F_SETFL, fcntl(impl_->from_child, F_GETFL) | O_NONBLOCK);
  if (rc != 0) fail("start", std::string("fork failed: ") + std::strerror(rc));
}

LineProcess::~LineProcess() = default;

void ExternalPolicy::start() {
  proc_ = std::make_unique<LineProcess>(command_, "external policy");
  const sim::ObservationLayout& layout = sim::observation_layout(task_);
  nlohmann::json hello = {{"type", "hello"},
                          {"protocol", std::string(kExternalProtocol)},
                          {"task", std::string(sim::task_name(task_))},
                          {"obs_dim", layout.size()},
                          {"action_dim", kActionDim},
                          {"horizon", sim::task_horizon(task_)},
                          {"control_dt_s", 0.05},
                          {"layout", nlohmann::json::parse(layout.to_json())}};
  send(hello.dump(), "hello", options_.hello_timeout_s);
  const std::string reply = receive(options_.hello_timeout_s, "hello");
  if (!is_ready_reply(reply))
    fail("hello", "expected {\"type\":\"ready\"}, got '" + excerpt(reply) + "'");
}

ExternalPolicy::~ExternalPolicy() = default;

std::string ExternalPolicy::sha256() const { return sha256_hex(command_); }

std::unique_ptr<Policy> ExternalPolicy::clone() const {
  {
    // a process that has only answered the hello is exactly what a new clone would start: the first
    // clone of an unused policy takes it over (the runner clones its prototype once per worker, so
    // this saves one start of the policy process per job; the prototype starts a new one if used)
    std::lock_guard<std::mutex> lock(handover_mutex_);
    if (proc_ && episode_ < 0 && step_ == 0)
      return std::unique_ptr<Policy>(new ExternalPolicy(command_, task_, options_, std::move(proc_)));
  }
  return std::make_unique<ExternalPolicy>(command_, task_, options_);
}

void ExternalPolicy::ensure_started() {
  std::lock_guard<std::mutex> lock(handover_mutex_);
  if (!proc_) start();
}

void LineProcess::fail(const std::string& what, const std::string& reason) const {
  throw std::runtime_error(role_ + " '" + command_ + "': " + what + ": " + reason);
}

void ExternalPolicy::fail(const std::string& what, const std::string& reason) { proc_->fail(what, reason); }
void ExternalPolicy::send(const std::string& line, const char* what, double timeout_s) { proc_->send(line, what, timeout_s); }
std::string ExternalPolicy::receive(double timeout_s, const char* what) { return proc_->receive(timeout_s, what); }

bool LineProcess::read_some(const char* what) {
  char chunk[4096];
  for (;;) {
    const ssize_t n = read(impl_->from_child, chunk, sizeof chunk);
    if (n > 0) {
      impl_->buffer.append(chunk, static_cast<std::size_t>(n));
      if (impl_->buffer.size() > kMaxReplyBytes) fail(what, "reply line longer than 1 MiB");
      return true;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return false;
    // end of stream: the process closed stdout or died; wait briefly for its status
    for (int i = 0; i < 50 && !impl_->poll_exit(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    fail(what, impl_->exited ? impl_->exit_text() + " before replying" : std::string("process closed its stdout"));
  }
}

void LineProcess::check_no_pending_output(const char* what) {
  // the protocol is strictly one reply per step request: whatever arrived since the last reply was
  // not asked for (a second reply, or a reply to a reset), and would make every later reply lag
  pollfd p{impl_->from_child, POLLIN, 0};
  while (impl_->buffer.empty() && poll(&p, 1, 0) > 0 && (p.revents & (POLLIN | POLLHUP | POLLERR)) != 0) {
    if (!read_some(what)) break;
  }
  if (!impl_->buffer.empty())
    fail(what, "protocol error: output that no request asked for (an extra reply?): '" + excerpt(impl_->buffer) + "'");
}

void LineProcess::send(const std::string& line, const char* what, double timeout_s) {
  check_no_pending_output(what);
  const std::string data = line + "\n";
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  std::size_t off = 0;
  while (off < data.size()) {
    if (g_interrupted.load()) fail(what, "interrupted (SIGINT or SIGTERM)");
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0)
      fail(what, "the process did not read its request within " + std::to_string(timeout_s).substr(0, 5) + " s (timeout)");
    // watch stdout too: a process that writes instead of reading would otherwise block both sides
    pollfd p[2] = {{impl_->to_child, POLLOUT, 0}, {impl_->from_child, POLLIN, 0}};
    const int r = poll(p, 2, static_cast<int>(std::min<long long>(left.count(), 100)));
    if (r < 0 && errno != EINTR) fail(what, std::string("poll failed: ") + std::strerror(errno));
    if (r <= 0) continue;
    if ((p[1].revents & (POLLIN | POLLHUP | POLLERR)) != 0 && read_some(what))
      fail(what, "protocol error: output before the request was read (an extra reply?): '" + excerpt(impl_->buffer) + "'");
    if ((p[0].revents & (POLLOUT | POLLERR | POLLHUP)) == 0) continue;
    const ssize_t n = write(impl_->to_child, data.data() + off, data.size() - off);
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN || errno == EWOULDBLOCK) continue;
      if (impl_->poll_exit()) fail(what, impl_->exit_text());
      fail(what, std::string("write failed: ") + std::strerror(errno));
    }
    off += static_cast<std::size_t>(n);
  }
}

std::string LineProcess::receive(double timeout_s, const char* what) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (true) {
    const auto nl = impl_->buffer.find('\n');
    if (nl != std::string::npos) {
      std::string line = impl_->buffer.substr(0, nl);
      impl_->buffer.erase(0, nl + 1);
      if (!impl_->buffer.empty())
        fail(what, "protocol error: more than one reply line to one request: '" + excerpt(impl_->buffer) + "'");
      return line;
    }
    if (g_interrupted.load()) fail(what, "interrupted (SIGINT or SIGTERM)");
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) fail(what, "no reply within " + std::to_string(timeout_s).substr(0, 5) + " s (timeout)");
    pollfd p{impl_->from_child, POLLIN, 0};
    const int r = poll(&p, 1, static_cast<int>(std::min<long long>(left.count(), 100)));
    if (r < 0 && errno != EINTR) fail(what, std::string("poll failed: ") + std::strerror(errno));
    if (r <= 0) continue;
    read_some(what);
  }
}

void ExternalPolicy::reset() {
  ensure_started();
  ++episode_;
  step_ = 0;
  const sim::ObservationLayout& layout = sim::observation_layout(task_);
  // no episode index: with one worker it would name the job's episode, and from it the dealt contract
  nlohmann::json msg = {{"type", "reset"},
                        {"task", std::string(sim::task_name(task_))},
                        {"layout", nlohmann::json::parse(layout.to_json())}};
  send(msg.dump(), "reset", options_.step_timeout_s);
}

Action ExternalPolicy::act(const Eigen::Ref<const Eigen::VectorXd>& obs) {
  check_observation(obs, task_);
  ensure_started();
  const std::string what = "step " + std::to_string(step_);
  nlohmann::json msg = {{"type", "step"}, {"t", step_}, {"obs", std::vector<double>(obs.data(), obs.data() + obs.size())}};
  send(msg.dump(), what.c_str(), options_.step_timeout_s);
  const std::string reply = receive(options_.step_timeout_s, what.c_str());
  Action out;
  try {
    out = parse_step_reply(reply);
  } catch (const std::invalid_argument& e) {
    fail(what, "bad reply (" + std::string(e.what()) + "): '" + excerpt(reply) + "'");
  }
  ++step_;
  return out;
}

}  // namespace actionshift::policy
