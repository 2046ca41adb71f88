// Tests for reference/core/io.h: inputs must be regular files of bounded size, outputs are
// checked before any work (no input overwritten, no two outputs on one file, the directory must
// exist), and text quoted in messages is escaped (issue #18).
#include "reference/core/io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace dentsim {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

namespace fs = std::filesystem;

class IoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("dentsim_io_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(path(name)) << text;
    return path(name);
  }
  fs::path dir_;
};

template <typename F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST_F(IoTest, ReadFileRefusesWhatIsNotARegularFile) {
  // /dev/zero used to fill memory until the process died; a FIFO used to hang (issue #18).
  EXPECT_EQ(error_of([] { read_file("/dev/zero"); }),
            "cannot read '/dev/zero': it is a character device; expected a regular file");
  const std::string fifo = path("pipe.stl");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(error_of([&] { read_file(fifo); }),
            "cannot read '" + fifo + "': it is a FIFO; expected a regular file");
  EXPECT_EQ(error_of([&] { read_file(dir_.string()); }),
            "cannot read '" + dir_.string() + "': it is a directory; expected a regular file");
  EXPECT_THAT(error_of([&] { read_file(path("missing")); }),
              HasSubstr("cannot read '" + path("missing") + "': No such file"));
}

TEST_F(IoTest, ReadFileHasASizeLimit) {
  const std::string f = write("ten.txt", "0123456789");
  EXPECT_EQ(read_file(f, 10), "0123456789");
  EXPECT_EQ(error_of([&] { read_file(f, 9); }),
            "cannot read '" + f + "': 10 bytes, more than the limit of 9 bytes");
}

TEST_F(IoTest, OutputThatIsAnInputIsRefused) {
  const std::string log = write("log.csv", "t_s\n");
  EXPECT_EQ(error_of([&] {
              check_output_paths({{"--json", log}}, {{"LOG", log}});
            }),
            "--json '" + log + "': is the input LOG '" + log + "'; refusing to overwrite an input");
  // The same file through another spelling of the path.
  const std::string other = dir_.string() + "/./log.csv";
  EXPECT_THAT(error_of([&] {
                check_output_paths({{"-o", other}}, {{"LOG", log}});
              }),
              HasSubstr("refusing to overwrite an input"));
  // Two outputs on one file (which does not exist yet).
  const std::string x = path("x.json");
  EXPECT_EQ(error_of([&] {
              check_output_paths({{"--json", x}, {"-o", x}});
            }),
            "-o '" + x + "': is also the output --json; each output needs its own file");
  EXPECT_EQ(error_of([&] {
              check_output_paths({{"--json", x}, {"-o", path("y.json")}});
            }),
            "(no error)");
  EXPECT_FALSE(fs::exists(x));  // checking writes nothing
}

TEST_F(IoTest, OutputDirectoryMustExistAndPathMustBeAFile) {
  const std::string missing = path("no/such/dir/r.json");
  EXPECT_EQ(error_of([&] {
              check_output_paths({{"--json", missing}});
            }),
            "--json '" + missing + "': directory '" + path("no/such/dir") + "' does not exist");
  EXPECT_EQ(error_of([&] {
              check_output_paths({{"-o", dir_.string()}});
            }),
            "-o '" + dir_.string() + "': is a directory; expected a file path");
  EXPECT_EQ(error_of([&] { check_output_paths({{"-o", ""}}, {{"LOG", ""}}); }), "(no error)");
}

TEST_F(IoTest, WriteFileAtomicLeavesNoTemporary) {
  const std::string f = write("r.json", "old");
  write_file_atomic(f, "new");
  std::ifstream in(f);
  std::string s;
  std::getline(in, s);
  EXPECT_EQ(s, "new");
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir_)) files += e.is_regular_file() ? 1 : 0;
  EXPECT_EQ(files, 1);
}

TEST(Printable, EscapesControlAndNonAsciiBytesAndCuts) {
  EXPECT_EQ(printable("vertex"), "vertex");
  EXPECT_EQ(printable("a\x1b[2Jb"), "a\\x1b[2Jb");
  EXPECT_EQ(printable(std::string("\0\xff", 2)), "\\x00\\xff");
  EXPECT_EQ(printable(std::string(100, 'x'), 10), std::string(10, 'x') + "...");
}

}  // namespace
}  // namespace dentsim
