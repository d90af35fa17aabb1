// Outputs: an output naming an input of the same run is refused before the run; every write is
// checked (a device that refuses the bytes fails the output); failed or interrupted runs leave no
// folder and no provisional file they created.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <future>
#include <string>
#include <thread>

#include "cli_helpers.hpp"
#include "microsim/common.hpp"
#include "microsim/io/output.hpp"

using namespace microsim;
using namespace microsim::testing;
namespace fs = std::filesystem;

namespace {

// A folder of this test's own (removed at the end of the program with the other temporaries).
std::string folder(const std::string& name) {
  const std::string d = temp_path("outputs", name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// A small periodic heightfield written by the program itself.
std::string small_surface(const std::string& dir) {
  const std::string s = dir + "/g.exr";
  const Result r = run_microsim("-q generate gaussian --resolution 32 --alpha 0.5 -o " + s);
  EXPECT_EQ(r.code, 0) << r.err;
  return s;
}

// Names in `dir` that start with ".tmp-" (the atomic writer's temporaries).
int temporaries_in(const std::string& dir) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(dir)) n += e.path().filename().string().rfind(".tmp-", 0) == 0;
  return n;
}

bool is_char_device(const std::string& p) {
  struct stat st;
  return stat(p.c_str(), &st) == 0 && S_ISCHR(st.st_mode);
}

// Runs `command` in the background, waits until `ready` exists (at most 60 s), sends `signal`
// and waits for the process: the interrupted run's exit status from the shell.
int interrupt_when_ready(const std::string& command, const std::string& ready, const std::string& signal) {
  const std::string script = binary() + " " + command + " >/dev/null 2>&1 & pid=$!; for i in $(seq 600); do "
                             "[ -e " + ready + " ] && break; sleep 0.1; done; kill -" + signal +
                             " $pid; wait $pid";
  const int status = std::system(("bash -c '" + script + "'").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

// --- an output naming an input -----------------------------------------------------------------

TEST(OutputNamingInput, SameSpellingIsRefusedWithExitTwoBeforeTheRun) {
  const std::string dir = folder("same");
  const std::string g = small_surface(dir);
  const std::string before = slurp(g);
  const Result r = run_microsim("measure ndf " + g + " -o " + g);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("-o " + g), std::string::npos) << r.err;        // the output option
  EXPECT_NE(r.err.find("input surface " + g), std::string::npos) << r.err;  // the input argument
  EXPECT_EQ(r.out, "");  // nothing measured
  EXPECT_EQ(slurp(g), before);
  EXPECT_EQ(temporaries_in(dir), 0);
}

TEST(OutputNamingInput, AnotherSpellingOfTheSamePathIsRefused) {
  const std::string dir = folder("spelling");
  const std::string g = small_surface(dir);
  fs::create_directories(dir + "/sub");
  const std::string before = slurp(g);
  const Result r = run_microsim("measure ndf " + g + " -o " + dir + "/sub/.././g.exr");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(slurp(g), before);
}

TEST(OutputNamingInput, ASymbolicLinkToTheInputIsRefusedBothWays) {
  const std::string dir = folder("link");
  const std::string g = small_surface(dir);
  const std::string link = dir + "/link.exr";
  fs::create_symlink(g, link);
  const std::string before = slurp(g);
  for (const std::string& args : {"measure ndf " + link + " -o " + g, "measure ndf " + g + " -o " + link}) {
    const Result r = run_microsim(args);
    EXPECT_EQ(r.code, 2) << args << ": " << r.err;
    EXPECT_EQ(slurp(g), before);
    EXPECT_TRUE(fs::is_symlink(link));
  }
}

TEST(OutputNamingInput, AHardLinkToTheInputIsRefused) {
  const std::string dir = folder("hardlink");
  const std::string g = small_surface(dir);
  fs::create_hard_link(g, dir + "/same.exr");
  const std::string before = slurp(g);
  const Result r = run_microsim("convert " + g + " -o " + dir + "/same.exr");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(slurp(g), before);
  EXPECT_EQ(fs::hard_link_count(g), 2u);  // not replaced by a new file
}

TEST(OutputNamingInput, TheSidecarOfAnInputMeshIsAnInput) {
  const std::string dir = folder("sidecar_in");
  const std::string mesh = dir + "/box.ply";
  ASSERT_EQ(run_microsim("-q generate box -o " + mesh).code, 0);
  const std::string before = slurp(mesh + ".json");
  const Result r = run_microsim("measure g1 " + mesh + " --theta 0 --rays 1000 -o " + mesh + ".json");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("sidecar"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(mesh + ".json"), before);
}

TEST(OutputNamingInput, TheSidecarAnOutputWouldWriteMustNotReplaceAnInput) {
  const std::string dir = folder("sidecar_out");
  // A preset whose name is the sidecar of the mesh the command writes.
  const std::string preset = dir + "/o.ply.json";
  { std::ofstream(preset) << "alpha = 0.5\nresolution = 16\n"; }
  const std::string before = slurp(preset);
  const Result r = run_microsim("generate gaussian --config " + preset + " -o " + dir + "/o.ply");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--config"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(preset), before);
  EXPECT_FALSE(exists(dir + "/o.ply"));
}

TEST(OutputNamingInput, MergeRefusesToWriteOverAPart) {
  const std::string dir = folder("merge");
  const std::string g = small_surface(dir);
  const std::string out = dir + "/m.json";
  for (const char* k : {"1/2", "2/2"})
    ASSERT_EQ(run_microsim("-q measure g1 " + g + " --theta 0 --rays 2000 --replicates 4 --shard " + k + " -o " + out).code, 0);
  const std::string part = out + ".shard-1-of-2.json";
  const std::string before = slurp(part);
  const Result r = run_microsim("merge " + part + " " + out + ".shard-2-of-2.json -o " + part);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("parts"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(part), before);
}

TEST(OutputNamingInput, ADifferentOutputIsAccepted) {
  const std::string dir = folder("different");
  const std::string g = small_surface(dir);
  const Result r = run_microsim("-q measure ndf " + g + " -o " + dir + "/d.json");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(exists(dir + "/d.json"));
}

// --- checked writes ----------------------------------------------------------------------------

TEST(CheckedWrites, ASmallRecordOnADeviceThatRefusesBytesFails) {
  if (!is_char_device("/dev/full")) GTEST_SKIP() << "no /dev/full here";
  // A few bytes stay in the stream's buffer until it is flushed: only the flush and the close
  // can see the failure.
  try {
    write_json("/dev/full", {{"a", 1}});
    ADD_FAILURE() << "writing /dev/full did not fail";
  } catch (const RuntimeFailure& e) {
    EXPECT_NE(std::string(e.what()).find("cannot write /dev/full"), std::string::npos) << e.what();
  }
  EXPECT_THROW(write_csv_rows("/dev/full", {{"rows", {{{"x", 1}}}}}), RuntimeFailure);
  EXPECT_TRUE(is_char_device("/dev/full"));  // written in place, never replaced by a rename
}

TEST(CheckedWrites, TheProgramFailsWithOneLineAndLeavesNoFileBesideALinkToAFullDevice) {
  if (!is_char_device("/dev/full")) GTEST_SKIP() << "no /dev/full here";
  const std::string dir = folder("devfull");
  const std::string g = small_surface(dir);
  const std::string link = dir + "/full.json";
  fs::create_symlink("/dev/full", link);
  const Result r = run_microsim("-q measure ndf " + g + " -o " + link);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_EQ(lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("cannot write " + link), std::string::npos) << r.err;
  EXPECT_TRUE(fs::is_symlink(link));  // the link was not replaced by a regular file
  EXPECT_TRUE(is_char_device("/dev/full"));
  EXPECT_EQ(temporaries_in(dir), 0);
}

TEST(CheckedWrites, AStreamLeftInErrorFailsTheOutputAndLeavesNothing) {
  const std::string dir = folder("badstream");
  const std::string path = dir + "/x.json";
  EXPECT_THROW(write_stream_atomically(path,
                                       [](std::ofstream& out) {
                                         out << "partial";
                                         out.setstate(std::ios::badbit);  // as a failed write does
                                       }),
               RuntimeFailure);
  EXPECT_FALSE(exists(path));
  EXPECT_EQ(temporaries_in(dir), 0);
}

TEST(CheckedWrites, AWriterThatCreatesNoFileFails) {
  const std::string dir = folder("nofile");
  EXPECT_THROW(write_atomically(dir + "/x.json", [](const std::string&) {}), RuntimeFailure);
  EXPECT_FALSE(exists(dir + "/x.json"));
}

TEST(CheckedWrites, AWriterMessageNamesTheOutputNotItsTemporary) {
  const std::string dir = folder("message");
  try {
    write_atomically(dir + "/x.exr", [](const std::string& tmp) { throw std::runtime_error("bad " + tmp); });
    ADD_FAILURE();
  } catch (const RuntimeFailure& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find(".tmp-"), std::string::npos) << what;
    EXPECT_NE(what.find("cannot write " + dir + "/x.exr"), std::string::npos) << what;
  }
}

// --- no leftovers ------------------------------------------------------------------------------

TEST(NoLeftovers, AFolderCreatedForOutputsGoesWhenTheTransactionFails) {
  const std::string dir = folder("created");
  {
    OutputTransaction t;
    ASSERT_TRUE(create_output_folder(dir + "/a/b"));
    write_json(dir + "/a/b/x.json", {{"a", 1}});
  }
  EXPECT_FALSE(exists(dir + "/a"));
  {
    OutputTransaction t;
    ASSERT_TRUE(create_output_folder(dir + "/a/b"));
    write_json(dir + "/a/b/x.json", {{"a", 1}});
    t.commit();
  }
  EXPECT_TRUE(exists(dir + "/a/b/x.json"));
}

TEST(NoLeftovers, AFolderThatExistedOrHoldsOtherFilesIsKept) {
  const std::string dir = folder("existing");
  {
    OutputTransaction t;
    ASSERT_TRUE(create_output_folder(dir + "/new"));
    std::ofstream(dir + "/new/foreign.txt") << "not the command's";
  }
  EXPECT_TRUE(exists(dir + "/new/foreign.txt"));
  {
    OutputTransaction t;
    ASSERT_TRUE(create_output_folder(dir));
  }
  EXPECT_TRUE(exists(dir));
}

TEST(NoLeftovers, ProvisionalFilesFollowTheEnclosingTransaction) {
  const std::string dir = folder("provisional");
  const std::string p = dir + "/s.json";
  {
    OutputTransaction outer;
    {
      OutputTransaction inner;
      write_json(p, {{"a", 1}});
      inner.place_provisionally();
    }
    EXPECT_TRUE(exists(p));  // in place at once (read back by the command)
  }
  EXPECT_FALSE(exists(p));  // the run did not succeed
  {
    OutputTransaction outer;
    {
      OutputTransaction inner;
      write_json(p, {{"a", 1}});
      inner.place_provisionally();
    }
    outer.commit();
  }
  EXPECT_TRUE(exists(p));
}

// Two commands on two threads (as Python calls without the GIL run them): each thread's writes
// join the transaction that thread opened, not the one opened last by any thread. Thread A opens
// its transaction, then B opens one (the most recent of the process), then A writes, commits and
// B ends uncommitted: A's file must be in place and B's gone.
TEST(NoLeftovers, EachThreadsWritesJoinTheTransactionItOpened) {
  const std::string dir = folder("threads");
  const std::string a_path = dir + "/a.json", b_path = dir + "/b.json";
  std::promise<void> a_opened, b_opened, a_done;
  std::thread b([&] {
    a_opened.get_future().wait();
    OutputTransaction t;
    b_opened.set_value();
    a_done.get_future().wait();
    write_json(b_path, {{"b", 1}});
  });  // not committed
  {
    OutputTransaction t;
    a_opened.set_value();
    b_opened.get_future().wait();
    write_json(a_path, {{"a", 1}});
    EXPECT_EQ(OutputTransaction::pending(a_path).empty(), false);  // seen from any thread
    t.commit();
  }
  a_done.set_value();
  b.join();
  EXPECT_TRUE(exists(a_path));
  EXPECT_FALSE(exists(b_path));
  EXPECT_EQ(temporaries_in(dir), 0);
}

TEST(NoLeftovers, DemoInterruptedLeavesNoOutputFolder) {
  const std::string dir = folder("demo_term");
  const std::string out = dir + "/demo";
  const int code = interrupt_when_ready("-q demo --resolution 256 --rays 50000000 --out-dir " + out, out, "TERM");
  EXPECT_NE(code, 0);
  EXPECT_FALSE(exists(out));
}

TEST(NoLeftovers, DemoFailingToWriteLeavesNoOutputFolder) {
  const std::string dir = folder("demo_fail");
  const std::string out = dir + "/a/demo";
  // Files of at most 4 KiB (ulimit -f, SIGXFSZ ignored so that the write fails with EFBIG): the
  // surface cannot be written, after the folders were created.
  const Result r = run_microsim("-q demo --resolution 64 --theta 0 --rays 1000 --out-dir " + out,
                                "trap '' XFSZ; ulimit -f 8;");
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("cannot write " + out + "/surface.exr"), std::string::npos) << r.err;
  EXPECT_FALSE(exists(dir + "/a"));
}

TEST(NoLeftovers, ValidateInterruptedRemovesTheSurfacesItGeneratedOnly) {
  const std::string dir = folder("validate_int");
  const std::string sd = dir + "/sd";
  fs::create_directories(sd);
  std::ofstream(sd + "/keep.txt") << "the user's";
  const int code = interrupt_when_ready("-q validate --suite smoke --rays 50000000 --surfaces-dir " + sd,
                                        sd + "/flat.exr", "INT");
  EXPECT_NE(code, 0);
  EXPECT_TRUE(exists(sd + "/keep.txt"));
  EXPECT_FALSE(exists(sd + "/flat.exr"));
  for (const auto& e : fs::directory_iterator(sd)) EXPECT_EQ(e.path().filename(), "keep.txt");
  // A folder the run created goes as a whole.
  const std::string created = dir + "/new/sd";
  EXPECT_NE(interrupt_when_ready("-q validate --suite smoke --rays 50000000 --surfaces-dir " + created,
                                 created + "/flat.exr", "INT"),
            0);
  EXPECT_FALSE(exists(dir + "/new"));
}
