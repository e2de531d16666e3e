// The one atomic writer (core/atomic_file.hpp): the target holds the old bytes or the new ones, never
// a mix; no temporary is left behind, on success or failure; a path that is not a regular file is
// refused without being touched; every failure is an InputError naming the target.
#include "actionshift/core/atomic_file.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace actionshift {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("actionshift_atomic_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::size_t entries(const fs::path& d) { return static_cast<std::size_t>(std::distance(fs::directory_iterator(d), fs::directory_iterator())); }

TEST(WriteFileAtomic, ReplacesTheWholeFileAndLeavesNoTemporary) {
  const fs::path d = fresh_dir("replace");
  const fs::path p = d / "x.json";
  write_file_atomic(p.string(), std::string(100000, 'a'));
  write_file_atomic(p.string(), "short\n");
  EXPECT_EQ(slurp(p), "short\n");
  EXPECT_EQ(entries(d), 1u);
  write_file_atomic(p.string(), "");  // an empty file is a file
  EXPECT_TRUE(fs::is_regular_file(p));
  EXPECT_EQ(fs::file_size(p), 0u);
  fs::remove_all(d);
}

TEST(WriteFileAtomic, FailuresNameTheTargetAndChangeNothing) {
  const fs::path d = fresh_dir("fail");
  // a missing directory
  const std::string missing = (d / "no" / "x.json").string();
  EXPECT_THAT([&] { write_file_atomic(missing, "x"); }, ::testing::ThrowsMessage<InputError>(HasSubstr(missing + ": cannot write file")));
  // a directory of that name is not replaced
  fs::create_directories(d / "dir");
  EXPECT_THAT([&] { write_file_atomic((d / "dir").string(), "x"); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("not a regular file")));
  EXPECT_TRUE(fs::is_directory(d / "dir"));
  // a FIFO is not replaced (and not opened: that could block)
  const fs::path fifo = d / "fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_THROW(write_file_atomic(fifo.string(), "x"), InputError);
  EXPECT_TRUE(fs::is_fifo(fifo));
  // a read-only directory: the old file stays as it was, no temporary appears
  const fs::path ro = d / "ro";
  fs::create_directories(ro);
  write_file_atomic((ro / "old.json").string(), "old\n");
  fs::permissions(ro, fs::perms::owner_read | fs::perms::owner_exec);
  if (::access(ro.c_str(), W_OK) != 0) {  // (root may write anyway)
    EXPECT_THROW(write_file_atomic((ro / "old.json").string(), "new\n"), InputError);
    EXPECT_EQ(slurp(ro / "old.json"), "old\n");
    EXPECT_EQ(entries(ro), 1u);
  }
  fs::permissions(ro, fs::perms::owner_all);
  // /dev/full: a device is refused before anything is written
  if (fs::exists("/dev/full")) {
    EXPECT_THAT([&] { write_file_atomic("/dev/full", "x"); }, ::testing::ThrowsMessage<InputError>(HasSubstr("/dev/full")));
  }
  fs::remove_all(d);
}

}  // namespace
}  // namespace actionshift
