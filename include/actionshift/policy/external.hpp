#pragma once
/// \file
/// A policy implemented by another process, in any language, speaking JSON lines over its stdin and
/// stdout (protocol "actionshift-policy-v1", docs/backbones.md; example:
/// docs/examples/external_policy.py). One object per line, UTF-8, '\n'-terminated:
///
///   -> {"type":"hello","protocol":"actionshift-policy-v1","task":"pick_cube","obs_dim":42,
///       "action_dim":7,"horizon":50,"control_dt_s":0.05,"layout":{"size":42,"fields":[...]}}
///   <- {"type":"ready"}                                  (within the hello timeout)
///   -> {"type":"reset","episode":0,"task":...,"layout":{...}}      (episode start; no reply)
///   -> {"type":"step","t":0,"obs":[42 numbers]}
///   <- {"action":[7 numbers]}                            (within the step timeout)
///   ...
///   (end: stdin is closed; the process should exit; its process group is killed after 2 s, or at
///    once after interrupt_external_policies())
///
/// The command runs under `/bin/sh -c`; its stderr is passed through. The process is started
/// when the policy is constructed (one process per clone, so one per worker thread). The first
/// clone of a policy that has not yet been reset or stepped takes over its greeted process instead
/// of starting another (the policy starts a new one if it is used after that), so a runner that
/// builds a prototype and clones it once per worker starts one process per worker, not one more. A process
/// that exits, closes stdout, exceeds the timeout, or replies with anything but a JSON object with
/// a 7-number finite "action" array makes act() throw std::runtime_error naming the command, the
/// step and the reason; nothing hangs: writing a request and waiting for its reply are both bounded
/// by the step timeout (the hello's by the hello timeout). The protocol is strictly one reply line
/// per step request: a second reply line, a reply to a reset, or output while a request is still
/// being written is a protocol error (a flooding process cannot make replies lag requests). SIGPIPE is ignored process-wide once an external policy is
/// created (writes to a dead process then fail with EPIPE instead of killing the caller).

#include "actionshift/policy/line_process.hpp"
#include "actionshift/policy/policy.hpp"

#include <chrono>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>

namespace actionshift::policy {

/// Process lifecycle (Linux). Each policy process runs `/bin/sh -c <command>` under a small `sh` wrapper
/// that leads a process group of its own and waits for it; the wrapper's parent-death signal
/// (PR_SET_PDEATHSIG) is SIGTERM, on which it SIGKILLs its group, so the policy dies with the runner
/// even when the runner is killed by SIGKILL. Processes that leave the group (setsid) are not
/// reached. The group is killed when the policy is destroyed. The functions below are for a
/// command's signal handlers.

/// Async-signal-safe. Every external policy stops waiting at once: a pending or later request fails
/// with "interrupted (SIGINT or SIGTERM)", and a destroyed policy's group is killed without the 2 s
/// grace (a policy blocked in a step would never exit on its own).
void interrupt_external_policies() noexcept;
/// Undoes interrupt_external_policies() (before a new job).
void clear_external_interrupt() noexcept;
/// Whether interrupt_external_policies() was called since the last clear_external_interrupt().
bool external_policies_interrupted() noexcept;
/// Async-signal-safe. SIGKILL to the process group of every live external policy process (for a
/// handler that is about to end the process).
void kill_external_policies() noexcept;

/// Protocol identifier sent in the hello message.
inline constexpr std::string_view kExternalProtocol = "actionshift-policy-v1";

/// Timeouts of the external-process protocol.
struct ExternalOptions {
  double hello_timeout_s{30.0};  ///< process start-up until the "ready" reply
  double step_timeout_s{10.0};   ///< one step request until its reply
};

/// One reply line to a step request: a JSON object with a 7-number finite "action" array (nesting
/// beyond kMaxJsonDepth, numbers outside a double's range and anything else are rejected).
/// throws std::invalid_argument(reason). Used by ExternalPolicy::act; public for tests and fuzzing.
Action parse_step_reply(std::string_view reply);
/// True for the hello's reply {"type":"ready"} (other keys ignored).
bool is_ready_reply(std::string_view reply);

/// The external-process policy (name "external:<command>", sha256 = SHA-256 of the command string).
class ExternalPolicy final : public Policy {
 public:
  /// Starts the process and performs the hello handshake. Throws std::runtime_error if the process
  /// cannot be started or does not answer the hello correctly in time.
  ExternalPolicy(std::string command, sim::TaskId task, ExternalOptions options = {});
  ~ExternalPolicy() override;
  ExternalPolicy(const ExternalPolicy&) = delete;
  ExternalPolicy& operator=(const ExternalPolicy&) = delete;

  void reset() override;
  Action act(const Eigen::Ref<const Eigen::VectorXd>& obs) override;
  std::string name() const override { return "external:" + command_; }
  std::string sha256() const override;
  sim::TaskId task() const override { return task_; }
  std::unique_ptr<Policy> clone() const override;

 private:
  ExternalPolicy(std::string command, sim::TaskId task, ExternalOptions options, std::unique_ptr<LineProcess> proc);
  void start();            // spawn the process and perform the hello (sets proc_)
  void ensure_started();   // start() again if the process was handed to a clone
  void send(const std::string& line, const char* what, double timeout_s);
  std::string receive(double timeout_s, const char* what);
  [[noreturn]] void fail(const std::string& what, const std::string& reason);

  std::string command_;
  sim::TaskId task_;
  ExternalOptions options_;
  mutable std::mutex handover_mutex_;     // clone() may run on several threads at once
  mutable std::unique_ptr<LineProcess> proc_;  // null once handed to a clone (until the next use)
  std::int64_t episode_{-1};
  int step_{0};
};

}  // namespace actionshift::policy
