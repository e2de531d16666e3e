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

namespace actionshift::policy {

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
