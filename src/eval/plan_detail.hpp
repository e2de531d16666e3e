#pragma once
// private to the eval layer: checks shared by the experiment parser and plan expansion

#include "actionshift/eval/experiment_yaml.hpp"

namespace actionshift::eval::detail {

// refuses an experiment whose grid exceeds kMaxPlanJobs, from the list sizes alone (InputError)
void check_job_count(const Experiment& ex);

}  // namespace actionshift::eval::detail
