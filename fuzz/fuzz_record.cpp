// JSON-lines episode records: one line (parse_record_line), and the result store's recovery of a
// whole JSONL file on open (repair of a torn last line, refusal of anything else)
#include "actionshift/eval/job.hpp"
#include "actionshift/eval/record.hpp"
#include "actionshift/eval/store.hpp"
#include "harness.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace {

struct Dir {
  std::filesystem::path path;
  Dir() {
    char tmpl[] = "/tmp/actionshift_fuzz_record_XXXXXX";
    const char* made = ::mkdtemp(tmpl);
    if (made == nullptr) std::abort();
    path = made;
  }
  ~Dir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

actionshift::eval::JobSpec job() {
  actionshift::eval::JobSpec j;
  j.task = "pick_cube";
  j.split = {"seen", std::string(64, 'a'), 3};
  j.method = "oracle";
  j.backbone = {"expert", std::string(64, 'b')};
  j.seed = 20260718;
  j.episodes = 8;
  return j;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace actionshift;
  static Dir dir;
  static const eval::JobSpec spec = job();
  const std::string_view bytes = fuzz::text(data, size);
  fuzz::expect_input_errors([&] { (void)eval::parse_record_line(bytes.substr(0, bytes.find('\n')), "fuzz.jsonl:1"); });
  // the same bytes as a job's JSONL file, opened (and repaired) by the store
  const std::filesystem::path file = dir.path / (eval::job_id(spec) + ".jsonl");
  std::filesystem::remove_all(dir.path);
  std::filesystem::create_directories(dir.path);
  { std::ofstream(file, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size())); }
  std::ostringstream log;
  fuzz::expect_input_errors([&] {
    eval::ResultStore store = eval::ResultStore::open(dir.path.string(), spec, eval::StoreOptions{false, &log});
    if (store.episodes_done() > spec.episodes) throw std::logic_error("store accepted more records than the job has");
  });
  return 0;
}
