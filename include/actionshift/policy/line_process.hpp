#pragma once
/// \file A child process that speaks one JSON object per line on its stdin and stdout: the transport
/// of external policies (external.hpp) and external methods (eval/external_method.hpp). The command
/// runs under `/bin/sh -c` in a process group of its own, led by a small shell that kills the whole
/// group when the runner dies (even by SIGKILL: its parent-death signal) or ends it; its stderr is
/// passed through. Every write and every wait for a reply is bounded by a timeout and by
/// interrupt_external_policies() (SIGINT/SIGTERM), so nothing hangs; the protocol is strictly one
/// reply line per request that asks for one, and output that no request asked for is an error.

#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace actionshift::policy {

/// Whether external processes (policies and methods) run in a sandbox: kAuto, in one when this
/// machine allows it, else without and with one warning on stderr; kOn, in one or not at all (the
/// start fails naming the reason); kOff, never.
enum class SandboxMode { kAuto, kOn, kOff };
/// "auto" | "on" | "off"; throws std::invalid_argument otherwise.
SandboxMode parse_sandbox_mode(std::string_view text);

/// The sandbox: the command runs in new user, mount and PID namespaces (as the same user), so it
/// sees no process outside its own (no /proc entry of the runner: its command line, environment,
/// open files, working directory or memory), each path of `hidden_paths` as an empty read-only
/// directory or empty file (the results directory, the seed file, the plan), and it inherits no file
/// descriptor but stdin, stdout and stderr (that last also without a sandbox). Paths that do not
/// exist when a process starts are not hidden: create them first. It is not a security boundary
/// against a process that can gain privileges; it closes the routes to a job's secrets that a user
/// method or policy could otherwise take as the same user.
struct SandboxConfig {
  SandboxMode mode{SandboxMode::kOff};
  std::vector<std::string> hidden_paths;
};
/// Process-wide: applies to the processes started after the call. Off until configured: the library
/// starts processes as it always did; `actionshift run` configures auto per job.
void configure_sandbox(SandboxConfig config);
/// Empty if this machine can make the sandbox, else why not (probed once, by starting a process).
const std::string& sandbox_unavailable_reason();

/// True while a live LineProcess leads process group `pgid` (an external policy or method still in
/// use: not a process left behind).
bool is_line_process_group(int pgid) noexcept;

class LineProcess {
 public:
  /// Starts `command`. `role` names it in errors ("external policy", "external method"). Throws
  /// std::runtime_error if the process cannot be started.
  LineProcess(std::string command, std::string role);
  /// Closes its stdin, gives it up to 2 s to exit (none after an interrupt), then kills its group.
  ~LineProcess();
  LineProcess(const LineProcess&) = delete;
  LineProcess& operator=(const LineProcess&) = delete;

  /// Writes `line` and a newline within `timeout_s`. Throws std::runtime_error
  /// ("<role> '<command>': <what>: <reason>") on a timeout, a dead process, an interrupt or output
  /// that arrived before the request was read.
  void send(const std::string& line, const char* what, double timeout_s);
  /// The next reply line (without its newline) within `timeout_s`; throws as send, also for a second
  /// line after it or a line longer than 1 MiB.
  std::string receive(double timeout_s, const char* what);
  /// Throws std::runtime_error("<role> '<command>': <what>: <reason>").
  [[noreturn]] void fail(const std::string& what, const std::string& reason) const;
  const std::string& command() const noexcept { return command_; }

 private:
  struct Impl;
  bool read_some(const char* what);
  void check_no_pending_output(const char* what);
  std::string command_, role_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace actionshift::policy
