// plan files (the JSON of `actionshift plan`, read by `run --plan`): parse_json_input + plan_from_json
#include "actionshift/core/json_input.hpp"
#include "actionshift/eval/job.hpp"
#include "actionshift/eval/plan_expand.hpp"
#include "actionshift/eval/plan_io.hpp"
#include "harness.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace actionshift;
  fuzz::expect_input_errors([&] {
    const eval::Plan plan = eval::plan_from_json(parse_json_input(fuzz::text(data, size), "fuzz.plan.json"), "fuzz.plan.json");
    for (const auto& job : plan.jobs) (void)eval::job_id(job.spec);
  });
  return 0;
}
