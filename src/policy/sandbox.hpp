#pragma once
// Internal: the sandbox of external processes (line_process.hpp, configure_sandbox), in two halves:
// what the runner prepares before fork() (every string and decision), and what the child does after
// fork() in a multi-threaded process (async-signal-safe system calls only, no allocation).

#include <string>
#include <vector>

namespace actionshift::policy::detail {

struct HiddenPath {
  std::string path;  // absolute
  bool directory{false};
};

// Everything the child needs, made before fork().
struct SandboxPlan {
  bool enabled{false};
  std::string uid_map, gid_map;  // "<id> <id> 1\n": the same user inside as outside
  std::vector<HiddenPath> hidden;
};

// The plan for a process started now, under the process-wide configuration. `role` names the
// process in the error thrown when the mode is kOn and no sandbox can be made (std::runtime_error);
// in kAuto the first such process prints one warning on stderr and runs without.
SandboxPlan sandbox_plan_for(const std::string& role);

// In the forked child, before execve. With a plan enabled: new user, mount and PID namespaces; the
// calling process stays outside the new PID namespace and waits for its first process (PID 1 inside),
// exiting with its status, and never returns; the first process mounts a new /proc and covers the
// hidden paths, then returns to exec the command. On any failure the child writes one line on stderr
// and exits with status 126. Without a plan: returns at once.
void enter_sandbox_in_child(const SandboxPlan& plan) noexcept;

}  // namespace actionshift::policy::detail
