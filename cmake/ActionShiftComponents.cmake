# The component graph of ActionShift, written once. Everything else is derived from it or checked
# against it:
#   - the build (CMakeLists.txt) checks after configuring that every target `actionshift_<c>` links
#     exactly the components listed here, and that the exported targets are these components;
#   - the installed package config (ActionShiftConfig.cmake) includes this file to resolve
#     find_package(ActionShift COMPONENTS ...) into the closure of the requested components;
#   - README.md's component table is rendered from it (test `install.components_doc`,
#     cmake/ActionShiftComponentsDoc.cmake);
#   - the install consumer test runs find_package(ActionShift COMPONENTS <c>) for every component.
#
# ACTIONSHIFT_COMPONENTS: every component, bottom to top (core is header-only).
# ACTIONSHIFT_COMPONENT_LINKS_<c>: the components <c> links directly (public or private).
# ACTIONSHIFT_COMPONENT_NEEDS_<c>: the external dependencies <c> adds to those of its links
#   (documentation; the find_dependency calls are in ActionShift<C>Deps.cmake, loaded per component).
# ACTIONSHIFT_COMPONENT_WHAT_<c>: one line of what it is (README).
cmake_policy(PUSH)
cmake_policy(SET CMP0057 NEW)  # if(... IN_LIST ...), whatever the including project's policies

set(ACTIONSHIFT_COMPONENTS core data adapt fit selftest sim policy eval render)

set(ACTIONSHIFT_COMPONENT_LINKS_core "")
set(ACTIONSHIFT_COMPONENT_NEEDS_core "Eigen, nlohmann_json, OpenSSL (crypto)")
set(ACTIONSHIFT_COMPONENT_WHAT_core "contracts, canonical JSON and hashes, decode/encode, grammar, manifests (header-only)")

set(ACTIONSHIFT_COMPONENT_LINKS_data core)
set(ACTIONSHIFT_COMPONENT_NEEDS_data "")
set(ACTIONSHIFT_COMPONENT_WHAT_data "the committed manifests and response calibrations, compiled in")

set(ACTIONSHIFT_COMPONENT_LINKS_adapt core)
set(ACTIONSHIFT_COMPONENT_NEEDS_adapt "")
set(ACTIONSHIFT_COMPONENT_WHAT_adapt "adapters, beliefs, probes, response calibration")

set(ACTIONSHIFT_COMPONENT_LINKS_fit core)
set(ACTIONSHIFT_COMPONENT_NEEDS_fit "Ceres")
set(ACTIONSHIFT_COMPONENT_WHAT_fit "the scale corrector's least-squares fit")

set(ACTIONSHIFT_COMPONENT_LINKS_selftest core adapt)
set(ACTIONSHIFT_COMPONENT_NEEDS_selftest "")
set(ACTIONSHIFT_COMPONENT_WHAT_selftest "plug-and-verify self-test")

set(ACTIONSHIFT_COMPONENT_LINKS_sim core)
set(ACTIONSHIFT_COMPONENT_NEEDS_sim "Bullet (bullet-float64), urdfdom, assimp, Threads")
set(ACTIONSHIFT_COMPONENT_WHAT_sim "the Bullet Panda, tasks, hidden-contract environment")

set(ACTIONSHIFT_COMPONENT_LINKS_policy sim)
set(ACTIONSHIFT_COMPONENT_NEEDS_policy "Threads")
set(ACTIONSHIFT_COMPONENT_WHAT_policy "backbones: experts, MLP and PPO weights, external policies, Gate 0")

set(ACTIONSHIFT_COMPONENT_LINKS_eval core data sim policy adapt fit)
set(ACTIONSHIFT_COMPONENT_NEEDS_eval "yaml-cpp, Threads")
set(ACTIONSHIFT_COMPONENT_WHAT_eval "jobs, runner, records, statistics, gates, plans")

set(ACTIONSHIFT_COMPONENT_LINKS_render sim eval)
set(ACTIONSHIFT_COMPONENT_NEEDS_render "Bullet, PNG, GIF (OSMesa is opened at run time)")
set(ACTIONSHIFT_COMPONENT_WHAT_render "headless renders, figures, reports")

# actionshift_component_closure(<out-var> <component>...): the components and everything they link,
# in ACTIONSHIFT_COMPONENTS order; unknown names are returned in <out-var>_UNKNOWN.
function(actionshift_component_closure out)
  set(todo ${ARGN})
  set(need "")
  set(unknown "")
  while(todo)
    list(POP_FRONT todo c)
    if(c IN_LIST need OR c IN_LIST unknown)
      continue()
    endif()
    if(NOT c IN_LIST ACTIONSHIFT_COMPONENTS)
      list(APPEND unknown ${c})
      continue()
    endif()
    list(APPEND need ${c})
    list(APPEND todo ${ACTIONSHIFT_COMPONENT_LINKS_${c}})
  endwhile()
  set(ordered "")
  foreach(c IN LISTS ACTIONSHIFT_COMPONENTS)
    if(c IN_LIST need)
      list(APPEND ordered ${c})
    endif()
  endforeach()
  set(${out} ${ordered} PARENT_SCOPE)
  set(${out}_UNKNOWN ${unknown} PARENT_SCOPE)
endfunction()
cmake_policy(POP)
