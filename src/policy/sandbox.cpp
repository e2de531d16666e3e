// the sandbox of external processes: configuration, the one-time probe, and the child's set-up
#include "sandbox.hpp"

#include "actionshift/policy/line_process.hpp"

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <sched.h>
#include <stdexcept>
#include <sys/mount.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

namespace actionshift::policy {

namespace {
std::mutex g_config_mutex;
SandboxConfig g_config;  // off until configured (actionshift run: auto)

// ---- the child's half: async-signal-safe calls only ----

void write_text(const char* text) noexcept {
  std::size_t n = std::strlen(text);
  while (n > 0) {
    const ssize_t w = ::write(STDERR_FILENO, text, n);
    if (w <= 0) return;
    text += w;
    n -= static_cast<std::size_t>(w);
  }
}

[[noreturn]] void fail_in_child(const char* step, const char* path = nullptr) noexcept {
  const int err = errno;
  char digits[16];
  int i = 15;
  digits[i] = '\0';
  int e = err < 0 ? 0 : err;
  do {
    digits[--i] = static_cast<char>('0' + e % 10);
    e /= 10;
  } while (e > 0 && i > 0);
  write_text("actionshift: sandbox: ");
  write_text(step);
  if (path) {
    write_text(" ");
    write_text(path);
  }
  write_text(" failed (errno ");
  write_text(digits + i);
  write_text(")\n");
  ::_exit(126);
}

bool write_file(const char* path, const char* text) noexcept {
  const int fd = ::open(path, O_WRONLY | O_CLOEXEC);
  if (fd < 0) return false;
  const std::size_t n = std::strlen(text);
  const ssize_t w = ::write(fd, text, n);
  ::close(fd);
  return w == static_cast<ssize_t>(n);
}

std::string id_map(unsigned id) { return std::to_string(id) + " " + std::to_string(id) + " 1\n"; }
}  // namespace

SandboxMode parse_sandbox_mode(std::string_view text) {
  if (text == "auto") return SandboxMode::kAuto;
  if (text == "on") return SandboxMode::kOn;
  if (text == "off") return SandboxMode::kOff;
  throw std::invalid_argument("expected auto, on or off (got '" + std::string(text) + "')");
}

void configure_sandbox(SandboxConfig config) {
  std::lock_guard<std::mutex> lock(g_config_mutex);
  g_config = std::move(config);
}

namespace detail {

void enter_sandbox_in_child(const SandboxPlan& plan) noexcept {
  if (!plan.enabled) return;
  if (::unshare(CLONE_NEWUSER | CLONE_NEWNS | CLONE_NEWPID) != 0) fail_in_child("unshare(user, mount, pid)");
  // the same user inside as outside (writing the group map needs setgroups denied first)
  if (!write_file("/proc/self/setgroups", "deny")) fail_in_child("write", "/proc/self/setgroups");
  if (!write_file("/proc/self/uid_map", plan.uid_map.c_str())) fail_in_child("write", "/proc/self/uid_map");
  if (!write_file("/proc/self/gid_map", plan.gid_map.c_str())) fail_in_child("write", "/proc/self/gid_map");
  // a change of credentials (the new user namespace) clears the parent-death signal: set it again
  const pid_t runner = ::getppid();
  ::prctl(PR_SET_PDEATHSIG, SIGTERM);
  if (::getppid() != runner) ::_exit(126);  // the runner died in between
  const pid_t inner = ::fork();  // the first process of the new PID namespace
  if (inner < 0) fail_in_child("fork");
  if (inner > 0) {
    // outside: keep the group's leader (the runner's pid for this process) alive while the inside
    // runs, ending with its status; die on the parent-death signal (SIGTERM) like the leader would
    ::close(STDIN_FILENO);
    ::close(STDOUT_FILENO);
    // this copy of the runner never execs: its signal handlers are the runner's, which would catch
    // the parent-death SIGTERM instead of ending it
    struct sigaction dfl {};
    dfl.sa_handler = SIG_DFL;
    sigemptyset(&dfl.sa_mask);
    for (const int sig : {SIGTERM, SIGINT, SIGHUP, SIGQUIT, SIGPIPE}) ::sigaction(sig, &dfl, nullptr);
    sigset_t none;
    sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    int status = 0;
    while (::waitpid(inner, &status, 0) < 0)
      if (errno != EINTR) ::_exit(126);
    ::_exit(WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status));
  }
  // inside, PID 1: when the process outside dies, so does this one (and with it the namespace)
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (::mount(nullptr, "/", nullptr, MS_REC | MS_PRIVATE, nullptr) != 0) fail_in_child("mount --make-rprivate", "/");
  if (::mount("proc", "/proc", "proc", MS_NOSUID | MS_NODEV | MS_NOEXEC, nullptr) != 0) fail_in_child("mount proc on", "/proc");
  for (const HiddenPath& h : plan.hidden) {
    const int rc = h.directory ? ::mount("tmpfs", h.path.c_str(), "tmpfs", MS_RDONLY | MS_NOSUID | MS_NODEV | MS_NOEXEC,
                                         "size=4k,mode=555")
                               : ::mount("/dev/null", h.path.c_str(), nullptr, MS_BIND, nullptr);
    if (rc != 0) fail_in_child("hiding", h.path.c_str());
  }
}

namespace {
// starts a process that makes an empty sandbox and exits; its stderr line is the reason it could not
std::string probe_sandbox() {
  SandboxPlan plan;
  plan.enabled = true;
  plan.uid_map = id_map(::geteuid());
  plan.gid_map = id_map(::getegid());
  int err_pipe[2];
  if (::pipe2(err_pipe, O_CLOEXEC) != 0) return std::string("pipe failed: ") + std::strerror(errno);
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (::dup2(err_pipe[1], STDERR_FILENO) < 0) ::_exit(126);
    enter_sandbox_in_child(plan);
    ::_exit(0);  // inside the sandbox: it could be made
  }
  ::close(err_pipe[1]);
  if (pid < 0) {
    ::close(err_pipe[0]);
    return std::string("fork failed: ") + std::strerror(errno);
  }
  std::string text;
  char buf[256];
  for (;;) {
    const ssize_t n = ::read(err_pipe[0], buf, sizeof buf);
    if (n > 0 && text.size() < 4096) text.append(buf, static_cast<std::size_t>(n));
    else if (n == 0 || (n < 0 && errno != EINTR)) break;
  }
  ::close(err_pipe[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return {};
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  const std::string prefix = "actionshift: sandbox: ";
  if (text.starts_with(prefix)) text = text.substr(prefix.size());
  // "... failed (errno N)" -> the errno's text
  const auto at = text.rfind("(errno ");
  if (at != std::string::npos) {
    const int e = std::atoi(text.c_str() + at + 7);
    text = text.substr(0, at) + "(" + std::strerror(e) + ")";
  }
  return text.empty() ? "the probe process ended with status " + std::to_string(status) : text;
}
}  // namespace

SandboxPlan sandbox_plan_for(const std::string& role) {
  SandboxConfig config;
  {
    std::lock_guard<std::mutex> lock(g_config_mutex);
    config = g_config;
  }
  SandboxPlan plan;
  if (config.mode == SandboxMode::kOff) return plan;
  const std::string& reason = sandbox_unavailable_reason();
  if (!reason.empty()) {
    if (config.mode == SandboxMode::kOn)
      throw std::runtime_error(role + ": --sandbox on: this machine cannot make the sandbox: " + reason);
    static std::once_flag warned;
    std::call_once(warned, [&] {
      std::cerr << "actionshift: warning: external processes run without a sandbox (" << reason
                << "): they can read the results directory, the seed file and the runner's /proc entries; "
                   "--sandbox on makes this an error\n";
    });
    return plan;
  }
  plan.enabled = true;
  plan.uid_map = id_map(::geteuid());
  plan.gid_map = id_map(::getegid());
  for (const std::string& p : config.hidden_paths) {
    std::error_code ec;
    const std::filesystem::path abs = std::filesystem::absolute(p, ec).lexically_normal();
    struct stat st {};
    if (ec || ::stat(abs.c_str(), &st) != 0) continue;  // not there: nothing to hide
    plan.hidden.push_back({abs.string(), S_ISDIR(st.st_mode)});
  }
  // a path inside a hidden directory is hidden with it (and could not be covered once that is)
  const auto inside = [&](const detail::HiddenPath& h) {
    return std::any_of(plan.hidden.begin(), plan.hidden.end(), [&](const detail::HiddenPath& dir) {
      if (!dir.directory || &dir == &h) return false;
      const auto rel = std::filesystem::path(h.path).lexically_relative(dir.path);
      return !rel.empty() && *rel.begin() != "..";
    });
  };
  std::vector<detail::HiddenPath> kept;
  for (const auto& h : plan.hidden)
    if (!inside(h) && std::none_of(kept.begin(), kept.end(), [&](const auto& k) { return k.path == h.path; })) kept.push_back(h);
  plan.hidden = std::move(kept);
  return plan;
}

}  // namespace detail

const std::string& sandbox_unavailable_reason() {
  static const std::string reason = detail::probe_sandbox();
  return reason;
}

}  // namespace actionshift::policy
