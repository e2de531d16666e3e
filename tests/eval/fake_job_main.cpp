// Test helper: runs the fake job of fake_episode.hpp, slowly if asked, so a test can SIGKILL it
// mid-run and resume it. Usage: actionshift_eval_fake_job OUT_DIR EPISODES THREADS SLEEP_MS
#include "fake_episode.hpp"

#include <cstdlib>
#include <exception>
#include <iostream>

int main(int argc, char** argv) {
  if (argc != 5) {
    std::cerr << "usage: actionshift_eval_fake_job OUT_DIR EPISODES THREADS SLEEP_MS\n";
    return 2;
  }
  using namespace actionshift::eval;
  try {
    RunOptions o;
    o.out_dir = argv[1];
    o.threads = static_cast<unsigned>(std::atoi(argv[3]));
    o.progress = ProgressMode::off;
    run_job(testing::fake_job(std::atoll(argv[2])), testing::fake_episode_fn(70, std::atoi(argv[4])), o);
  } catch (const std::exception& e) {
    std::cerr << "actionshift_eval_fake_job: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
