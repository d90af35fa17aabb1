// Output layer: atomic writes, CSV mirroring JSON rows, self-describing EXR tables.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <sys/stat.h>
#include <unistd.h>

#include "microsim/common.hpp"
#include "microsim/io/json_input.hpp"
#include "microsim/io/output.hpp"
#include "cli_helpers.hpp"  // removes this program's temporary files at exit

using namespace microsim;

namespace {
std::string tmp(const std::string& name) {
  return ::testing::TempDir() + "microsim_io_" + std::to_string(getpid()) + "_" + name;
}
bool exists(const std::string& p) {
  struct stat st;
  return stat(p.c_str(), &st) == 0;
}
std::string slurp(const std::string& p) {
  std::ifstream f(p);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}
}  // namespace

TEST(Output, FailedWriteLeavesNothingBehind) {
  std::string path = tmp("never.json");
  std::remove(path.c_str());
  EXPECT_THROW(write_atomically(path,
                                [](const std::string& t) {
                                  std::ofstream(t) << "half";
                                  throw RuntimeFailure("boom");
                                }),
               RuntimeFailure);
  EXPECT_FALSE(exists(path));
  // ... and no temporary either (.tmp-PID-N-never.json).
  const std::string prefix = ".tmp-" + std::to_string(getpid()) + "-";
  for (const auto& e : std::filesystem::directory_iterator(::testing::TempDir())) {
    const std::string name = e.path().filename().string();
    EXPECT_FALSE(name.rfind(prefix, 0) == 0 && name.size() > 10 &&
                 name.compare(name.size() - 10, 10, "never.json") == 0)
        << name;
  }
}

TEST(Output, FailedWriteKeepsThePreviousFile) {
  std::string path = tmp("keep.json");
  write_json(path, {{"a", 1}});
  EXPECT_THROW(write_atomically(path, [](const std::string&) { throw RuntimeFailure("x"); }),
               RuntimeFailure);
  EXPECT_EQ(Json::parse(slurp(path))["a"], 1);
  std::remove(path.c_str());
}

TEST(Output, CsvMirrorsJsonRowsAndSkipsNestedFields) {
  Json j = {{"rows",
                       {{{"theta_deg", 10}, {"g1", 0.5}, {"bins", {1, 2}}},
                        {{"theta_deg", 20}, {"g1", 0.25}, {"smith_nominal", nullptr}}}}};
  std::string path = tmp("rows.csv");
  write_csv_rows(path, j);
  EXPECT_EQ(slurp(path), "theta_deg,g1,smith_nominal\n10,0.5,\n20,0.25,\n");
  std::remove(path.c_str());
}

TEST(Output, ExrTableRoundTripWithAttributes) {
  ExrTable t;
  t.width = 3;
  t.height = 2;
  t.channel_names = {"D", "D_stderr"};
  t.channels = {{1, 2, 3, 4, 5, 6}, {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f}};
  t.attributes = {{"alpha", 0.5}, {"parameterization", "theta rows"}, {"nested", {{"k", 1}}}};
  std::string path = tmp("t.exr");
  write_exr(path, t);
  ExrTable r = read_exr(path);
  EXPECT_EQ(r.width, 3);
  EXPECT_EQ(r.height, 2);
  ASSERT_EQ(r.channel_names.size(), 2u);
  for (std::size_t c = 0; c < 2; ++c) {
    auto it = std::find(t.channel_names.begin(), t.channel_names.end(), r.channel_names[c]);
    ASSERT_NE(it, t.channel_names.end());
    EXPECT_EQ(r.channels[c], t.channels[it - t.channel_names.begin()]);
  }
  EXPECT_DOUBLE_EQ(r.attributes["alpha"].get<double>(), 0.5);
  EXPECT_EQ(r.attributes["parameterization"], "theta rows");
  EXPECT_EQ(Json::parse(r.attributes["nested"].get<std::string>())["k"], 1);
  std::remove(path.c_str());
}

TEST(Output, ExtensionIsCaseInsensitiveAndIgnoresFolders) {
  EXPECT_EQ(extension_of("a/b.c/file.JSON"), "json");
  EXPECT_EQ(extension_of("a/b.c/file"), "");
}

// A corrupt EXR header declaring a string attribute larger than the file (here 2 GB in a file
// of a few hundred bytes) is refused before OpenEXR allocates the declared size; the same file
// with its true size reads.
TEST(Output, ExrAttributeLargerThanTheFileIsRefused) {
  ExrTable t;
  t.width = 2;
  t.height = 2;
  t.channel_names = {"Z"};
  t.channels = {{0, 1, 2, 3}};
  t.attributes = {{"note", "abcdefgh"}};
  const std::string path = tmp("huge-attribute.exr");
  write_exr(path, t);
  EXPECT_EQ(read_exr(path).attributes["note"], "abcdefgh");
  std::string bytes = slurp(path);
  const std::string key("note\0string\0", 12);
  const std::size_t at = bytes.find(key);
  ASSERT_NE(at, std::string::npos);
  ASSERT_EQ(bytes[at + 12], 8);  // little-endian int32 size of "abcdefgh"
  bytes[at + 12] = '\xf0';
  bytes[at + 13] = bytes[at + 14] = '\xff';
  bytes[at + 15] = '\x7f';
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
  try {
    read_exr(path);
    ADD_FAILURE() << "a 2 GB attribute in a short file was accepted";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("attribute 'note' declares 2147483632 bytes"), std::string::npos)
        << e.what();
  }
  std::remove(path.c_str());
}

namespace {
// `levels` arrays (or objects) nested inside each other around a number.
std::string nested(int levels, bool objects) {
  std::string open, close;
  for (int i = 0; i < levels; ++i) {
    open += objects ? "{\"a\": " : "[";
    close += objects ? "}" : "]";
  }
  return open + "1" + close;
}
}  // namespace

TEST(JsonInput, AcceptsUpToTheDepthLimitAndRefusesOneLevelMore) {
  const microsim::JsonLimits limits{8, 1 << 20, false};
  for (bool objects : {false, true}) {
    EXPECT_NO_THROW(microsim::parse_json_input(nested(8, objects), "doc", limits));
    try {
      microsim::parse_json_input(nested(9, objects), "doc.json", limits);
      ADD_FAILURE() << "9 levels accepted with a limit of 8";
    } catch (const microsim::UsageError& e) {
      EXPECT_NE(std::string(e.what()).find("doc.json nests"), std::string::npos) << e.what();
    }
  }
  // The default limit refuses a document 100,000 levels deep without exhausting the stack.
  EXPECT_THROW(microsim::parse_json_input(nested(100000, false), "deep"), microsim::UsageError);
  // The parsed document is the same as the unchecked parser's.
  EXPECT_EQ(microsim::parse_json_input(nested(8, true), "doc", limits), microsim::Json::parse(nested(8, true)));
}

TEST(JsonInput, RefusesTextLargerThanTheSizeLimitFromAStringOrAStream) {
  const microsim::JsonLimits limits{64, 100, false};
  const std::string fits = "[" + std::string(98, ' ') + "]", over = fits + " ";
  EXPECT_NO_THROW(microsim::parse_json_input(fits, "doc", limits));
  EXPECT_THROW(microsim::parse_json_input(over, "doc", limits), microsim::UsageError);
  std::istringstream in_fits(fits), in_over(over);
  EXPECT_NO_THROW(microsim::parse_json_input(in_fits, "doc", limits));
  EXPECT_THROW(microsim::parse_json_input(in_over, "doc", limits), microsim::UsageError);
  // Malformed text is the parser's own error, for the caller's message.
  EXPECT_THROW(microsim::parse_json_input("{\"a\": ", "doc", limits), microsim::Json::parse_error);
}
