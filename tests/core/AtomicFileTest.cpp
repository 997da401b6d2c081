#include "brittle/core/AtomicFile.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

namespace brittle {
namespace {

namespace fs = std::filesystem;

class AtomicFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() / ("brittle-atomic-file-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }

  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
    return out;
  }
  static std::string bytes(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }

  fs::path dir;
};

TEST_F(AtomicFileTest, ReplacesTheTargetAndLeavesNoTemporary) {
  const fs::path target = dir / "a.json";
  ASSERT_TRUE(writeFileAtomically(target, "one"));
  ASSERT_TRUE(writeFileAtomically(target, "two"));
  EXPECT_EQ(bytes(target), "two");
  EXPECT_EQ(names(), std::vector<std::string>{"a.json"});
}

TEST_F(AtomicFileTest, AFailedWriteLeavesTheTargetAndNoTemporary) {
  const fs::path target = dir / "a.h5";
  ASSERT_TRUE(writeFileAtomically(target, "old"));
  const Status st = writeAtomically(target, [](const fs::path& temporary) -> Status {
    std::ofstream(temporary) << "half";
    return makeError(ErrorCode::PackIoError, "disk full");
  });
  ASSERT_FALSE(st);
  EXPECT_EQ(st.error().message, "disk full");
  EXPECT_THROW((void)writeAtomically(target, [](const fs::path& temporary) -> Status {
                 std::ofstream(temporary) << "half";
                 throw std::runtime_error("thrown");
               }),
               std::runtime_error);
  EXPECT_EQ(bytes(target), "old");
  EXPECT_EQ(names(), std::vector<std::string>{"a.h5"});
}

TEST_F(AtomicFileTest, AWriteIntoAMissingDirectoryIsAnIoError) {
  const Status st = writeFileAtomically(dir / "missing" / "a.json", "x");
  ASSERT_FALSE(st);
  EXPECT_EQ(st.error().code, ErrorCode::PackIoError);
}

}  // namespace
}  // namespace brittle
