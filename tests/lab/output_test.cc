// OutputDir: a folder appears whole on Commit or not at all; it replaces only
// a folder vlab wrote whose entries are all vlab's; a folder that appeared at
// the path during the run is kept and the run's files go to a sibling; any
// name the file system takes works (a short staging name); staging folders of
// dead runs are removed, those of live runs never.
#include "core/core_errors.h"
#include "lab/outputs/lab_output.h"
#include "lab/outputs/lab_output_fs.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <set>
#include <string>

#include "test_util.h"

namespace vlab::lab::output_test {
namespace {

namespace fs = std::filesystem;
using vlab::testing::Entries;
using vlab::testing::ReadFile;
using vlab::testing::TempDir;
using vlab::testing::WriteFile;

bool Has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// A finished output folder at `dir` holding `files` (name -> text), as a run leaves it.
void Committed(const std::string& dir, const std::set<std::string>& files) {
  auto out = OutputDir::Create(dir);
  for (const std::string& f : files) {
    fs::create_directories(fs::path(out->File(f)).parent_path());
    WriteFile(out->File(f), "vlab's " + f);
  }
  ASSERT_EQ(out->Commit(), fs::path(dir).lexically_normal().string());
  ASSERT_EQ(out->note(), "");
}

std::string InputErrorOf(const std::string& dir) {
  try {
    OutputDir::Create(dir);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(OutputDirTest, FilesAppearOnlyOnCommit) {
  TempDir tmp;
  const std::string final_dir = tmp / "out/run";
  auto out = OutputDir::Create(final_dir);
  EXPECT_EQ(out->final_dir(), final_dir);
  const std::string file = out->File("log.csv");
  WriteFile(file, "time\n0\n");
  EXPECT_FALSE(fs::exists(final_dir));
  EXPECT_EQ(fs::path(file).parent_path().parent_path(), fs::path(tmp / "out"));  // staging is beside the result
  const std::string staging = fs::path(file).parent_path().filename().string();
  EXPECT_EQ(staging.rfind(".vlab-" + std::to_string(::getpid()) + "-", 0), 0u) << staging;
  EXPECT_TRUE(output_fs::IsStagingName(staging)) << staging;
  EXPECT_EQ(Entries(tmp / "out"), std::set<std::string>{staging});

  EXPECT_EQ(out->Commit(), final_dir);
  EXPECT_EQ(out->note(), "");
  EXPECT_EQ(ReadFile(final_dir + "/log.csv"), "time\n0\n");
  EXPECT_EQ(Entries(tmp / "out"), std::set<std::string>{"run"});
  EXPECT_EQ(Entries(final_dir), (std::set<std::string>{"log.csv", kOutputMarker}));
  EXPECT_EQ(output_fs::ReadManifest(final_dir), std::set<std::string>{"log.csv"});  // the list of what it wrote
  out.reset();  // destruction after Commit removes nothing
  EXPECT_EQ(ReadFile(final_dir + "/log.csv"), "time\n0\n");
}

TEST(OutputDirTest, CommitReplacesPreviousFolder) {
  TempDir tmp;
  const std::string final_dir = tmp / "run";
  Committed(final_dir, {"old.txt", "log.csv", "cam/rgb_000000.png"});  // a previous run's folder
  {
    auto out = OutputDir::Create(final_dir);
    WriteFile(out->File("log.csv"), "new log");
    EXPECT_EQ(ReadFile(final_dir + "/log.csv"), "vlab's log.csv");  // untouched until Commit
    EXPECT_EQ(out->Commit(), final_dir);
  }
  EXPECT_EQ(Entries(final_dir), (std::set<std::string>{"log.csv", kOutputMarker}));  // nothing of the old mixed in
  EXPECT_EQ(ReadFile(final_dir + "/log.csv"), "new log");
  EXPECT_EQ(Entries(tmp.path()), std::set<std::string>{"run"});  // no set-aside or staging folder left
}

TEST(OutputDirTest, DestructionWithoutCommitLeavesPreviousResult) {
  TempDir tmp;
  const std::string final_dir = tmp / "run";
  Committed(final_dir, {"log.csv"});
  std::string staging;
  {
    auto out = OutputDir::Create(final_dir);
    staging = fs::path(out->File("x")).parent_path().string();
    WriteFile(out->File("log.csv"), "half writ");
    fs::create_directory(out->File("sub"));
    WriteFile(out->File("sub/y"), "y");
    EXPECT_TRUE(fs::exists(staging));
  }
  EXPECT_FALSE(fs::exists(staging));
  EXPECT_EQ(Entries(tmp.path()), std::set<std::string>{"run"});
  EXPECT_EQ(ReadFile(final_dir + "/log.csv"), "vlab's log.csv");

  // and with no previous result, nothing at all remains
  TempDir fresh;
  {
    auto out = OutputDir::Create(fresh / "run");
    WriteFile(out->File("log.csv"), "x");
  }
  EXPECT_TRUE(Entries(fresh.path()).empty());
}

// vlab replaces only what it wrote: a folder with entries and no marker, or a file, is refused
// before anything is written; an empty folder is taken
TEST(OutputDirTest, NeverReplacesWhatVlabDidNotWrite) {
  TempDir tmp;
  const std::string mine = tmp / "mine";
  fs::create_directory(mine);
  WriteFile(mine + "/notes.txt", "a user's own file");
  WriteFile(tmp / "file", "a file");
  EXPECT_TRUE(Has(InputErrorOf(mine), "output folder '" + mine + "': exists and is not an output folder"));
  EXPECT_TRUE(Has(InputErrorOf(tmp / "file"), "output folder '" + (tmp / "file") + "': exists and is not a folder"));
  // a marker without the list (a vlab older than it): vlab cannot tell a user's files from its own
  fs::create_directory(tmp / "older");
  WriteFile(tmp / "older/.vlab-output", "This folder was written by vlab.\n");
  WriteFile(tmp / "older/log.csv", "x");
  EXPECT_TRUE(Has(InputErrorOf(tmp / "older"), "without the list of what vlab wrote there"));
  EXPECT_EQ(ReadFile(mine + "/notes.txt"), "a user's own file");
  EXPECT_EQ(ReadFile(tmp / "file"), "a file");
  EXPECT_EQ(Entries(tmp.path()), (std::set<std::string>{"mine", "file", "older"}));  // no staging folder either

  fs::create_directory(tmp / "empty");
  auto out = OutputDir::Create(tmp / "empty");
  WriteFile(out->File("log.csv"), "x");
  EXPECT_EQ(out->Commit(), tmp / "empty");
  EXPECT_EQ(Entries(tmp / "empty"), (std::set<std::string>{"log.csv", kOutputMarker}));
}

// files a user adds to a folder vlab wrote: the next run into it is refused (exit 2), naming them
TEST(OutputDirTest, FilesAddedToAVlabFolderAreNeverDeleted) {
  TempDir tmp;
  const std::string run = tmp / "run";
  Committed(run, {"log.csv", "summary.json", "cam/rgb_000000.png"});
  WriteFile(run + "/my_notes.txt", "notes");
  fs::create_directory(run + "/analysis");
  WriteFile(run + "/analysis/fig.py", "plot()");
  WriteFile(run + "/cam/mine.txt", "in a folder vlab wrote");
  const std::string error = InputErrorOf(run);
  EXPECT_TRUE(Has(error, "output folder '" + run +
                             "': holds entries vlab did not write: analysis/fig.py, "
                             "cam/mine.txt, my_notes.txt; vlab replaces only what it wrote"))
      << error;
  EXPECT_EQ(Entries(tmp.path()), std::set<std::string>{"run"});  // nothing written
  // the user's files go: the folder is vlab's again
  fs::remove_all(run + "/analysis");
  fs::remove(run + "/my_notes.txt");
  fs::remove(run + "/cam/mine.txt");
  fs::create_directory(run + "/empty_folder");  // (an empty folder holds nobody's files)
  EXPECT_EQ(InputErrorOf(run), "(no error)");

  // a file added while a run writes: that run's files go to a sibling, the user's stay
  auto out = OutputDir::Create(run);
  WriteFile(out->File("log.csv"), "this run");
  WriteFile(run + "/added_meanwhile.txt", "mine");
  EXPECT_EQ(out->Commit(), run + ".2");
  EXPECT_TRUE(Has(out->note(), "holds entries vlab did not write: added_meanwhile.txt")) << out->note();
  EXPECT_TRUE(Has(out->note(), "this run's files are in '" + run + ".2'")) << out->note();
  EXPECT_EQ(ReadFile(run + "/added_meanwhile.txt"), "mine");
  EXPECT_EQ(ReadFile(run + ".2/log.csv"), "this run");
}

// `vlab render`'s default folder sits inside a run's (out/NAME/render/CAMERA): vlab's by its own list
TEST(OutputDirTest, NestedOutputFolderIsVlabs) {
  TempDir tmp;
  const std::string run = tmp / "run";
  Committed(run, {"log.csv"});
  Committed(run + "/render/overview", {"rgb_000000.png", "frames.csv"});
  EXPECT_EQ(InputErrorOf(run), "(no error)");
  WriteFile(run + "/render/overview/extra.png", "a user's");
  EXPECT_TRUE(Has(InputErrorOf(run), "holds entries vlab did not write: render/overview/extra.png"));
}

// a file vlab writes into a finished folder after the run (vlab golden --keep's golden_log.csv)
TEST(OutputDirTest, AFileAddedToTheListIsVlabs) {
  TempDir tmp;
  const std::string run = tmp / "run";
  Committed(run, {"log.csv"});
  WriteFile(run + "/golden_log.csv", "thinned");
  EXPECT_TRUE(Has(InputErrorOf(run), "holds entries vlab did not write: golden_log.csv"));
  EXPECT_EQ(AddToOutputList(run, "golden_log.csv"), "");
  EXPECT_EQ(InputErrorOf(run), "(no error)");
  EXPECT_TRUE(Has(AddToOutputList(tmp.path(), "x"), "has no list of what vlab wrote"));
}

// two runs into one folder: the second to finish keeps the first's folder and takes DIR.2
// (DIR.3 when DIR.2 is taken); a foreign folder that appeared meanwhile is kept likewise
TEST(OutputDirTest, AFolderPutThereDuringTheRunIsKept) {
  TempDir tmp;
  const std::string dir = tmp / "res";
  auto first = OutputDir::Create(dir);
  auto second = OutputDir::Create(dir);
  auto third = OutputDir::Create(dir);
  WriteFile(first->File("log.csv"), "first");
  WriteFile(second->File("log.csv"), "second");
  WriteFile(third->File("log.csv"), "third");
  EXPECT_EQ(second->Commit(), dir);
  EXPECT_EQ(first->Commit(), dir + ".2");
  EXPECT_TRUE(Has(first->note(), "output folder '" + dir +
                                     "': another run put its folder there while this one ran; "
                                     "this run's files are in '" +
                                     dir + ".2'"))
      << first->note();
  EXPECT_EQ(third->Commit(), dir + ".3");
  EXPECT_EQ(ReadFile(dir + "/log.csv"), "second");
  EXPECT_EQ(ReadFile(dir + ".2/log.csv"), "first");
  EXPECT_EQ(ReadFile(dir + ".3/log.csv"), "third");

  auto late = OutputDir::Create(tmp / "late");
  WriteFile(late->File("log.csv"), "kept");
  fs::create_directory(tmp / "late");
  WriteFile(tmp / "late/theirs.txt", "theirs");
  EXPECT_EQ(late->Commit(), tmp / "late.2");
  late.reset();
  EXPECT_EQ(ReadFile(tmp / "late/theirs.txt"), "theirs");
  EXPECT_EQ(ReadFile(tmp / "late.2/log.csv"), "kept");
  EXPECT_EQ(Entries(tmp.path()), (std::set<std::string>{"res", "res.2", "res.3", "late", "late.2"}));
}

TEST(OutputDirTest, NamesTheFileSystemTakes) {
  TempDir tmp;
  // the trailing slash tab completion adds names the same folder
  auto out = OutputDir::Create(tmp / "results/");
  EXPECT_EQ(out->final_dir(), tmp / "results");
  EXPECT_EQ(out->Commit(), tmp / "results");
  // 255 bytes, the longest name of most file systems (NAME_MAX): the staging name is short
  const std::string longest(255, 'n');
  auto long_out = OutputDir::Create(tmp / longest);
  WriteFile(long_out->File("log.csv"), "x");
  EXPECT_EQ(long_out->Commit(), tmp / longest);
  EXPECT_EQ(ReadFile(tmp / (longest + "/log.csv")), "x");
  // no sibling name fits beside it: a run that finds it taken keeps its files in its staging folder
  auto a = OutputDir::Create(tmp / longest);
  auto b = OutputDir::Create(tmp / longest);
  WriteFile(b->File("log.csv"), "b");
  a->Commit();
  const std::string kept = b->Commit();
  EXPECT_EQ(kept, b->staging_dir());
  EXPECT_TRUE(Has(b->note(), "no sibling name is free: this run's files are in '" + kept + "'")) << b->note();
  EXPECT_EQ(ReadFile(kept + "/log.csv"), "b");
  // (kept there for good: a staging folder with its list is never removed as stale)
  OutputDir::Create(tmp / "other");
  EXPECT_EQ(ReadFile(kept + "/log.csv"), "b");

  for (const std::string bad : {"", ".", "..", "out/..", "/"}) {
    const std::string error = InputErrorOf(bad);
    EXPECT_TRUE(Has(error, "output folder '" + bad + "'")) << error;
  }
}

// a run that died (SIGKILL) left its staging folder: the next run into the same parent removes it;
// a live run's, a finished run's kept files and names vlab does not make are left alone
TEST(OutputDirTest, StagingFoldersOfDeadRunsAreRemoved) {
  TempDir tmp;
  const pid_t child = ::fork();
  if (child == 0) {
    auto out = OutputDir::Create(tmp / "a");
    WriteFile(out->File("log.csv"), "half");
    ::_exit(0);  // as SIGKILL would: no destructor, the staging folder stays
  }
  ASSERT_GT(child, 0);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  const std::set<std::string> left = Entries(tmp.path());
  ASSERT_EQ(left.size(), 1u);
  EXPECT_EQ(left.begin()->rfind(".vlab-" + std::to_string(child) + "-", 0), 0u) << *left.begin();

  auto live = OutputDir::Create(tmp / "b");
  const std::string live_staging = fs::path(live->staging_dir()).filename().string();
  fs::create_directory(tmp / ".vlab-notes");
  WriteFile(tmp / ".vlab-notes/.vlab-output", "");
  fs::create_directory(tmp / ".vlab-1-99");  // killed between its mkdir and its marker: empty
  fs::create_directory(tmp / ".vlab-2-5");   // the name, but no marker and a file: not vlab's
  WriteFile(tmp / ".vlab-2-5/x", "x");
  auto other = OutputDir::Create(tmp / "c");  // removes the dead runs' folders, not the live one's
  EXPECT_EQ(Entries(tmp.path()),
            (std::set<std::string>{live_staging, fs::path(other->staging_dir()).filename().string(), ".vlab-notes",
                                   ".vlab-2-5"}));
  EXPECT_EQ(output_fs::RemoveStaleStaging(tmp.path()), std::vector<std::string>{});
}

}  // namespace
}  // namespace vlab::lab::output_test
