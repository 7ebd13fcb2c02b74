// A full disk: ingest into a database on a tiny tmpfs (mounted in a private
// user + mount namespace, so no root is needed). The list that does not fit
// fails with a clear error naming the database; what was recorded before is
// intact and nothing is half-written.
#include <gtest/gtest.h>

#include <cstdlib>

#include "db/database.h"
#include "tests/test_util.h"

namespace doasido {
namespace {

using testing::DoasidoBin;
using testing::TempDir;
using testing::WriteFile;

std::string List(int rows, const std::string& prefix) {
  std::string text = "url,id,start_frame,end_frame,note\n";
  for (int i = 0; i < rows; ++i) {
    text += "https://example.org/" + prefix + std::to_string(i % 50) + ".mp4," + prefix +
            std::to_string(i) + "," + std::to_string(i) + "," + std::to_string(i + 5) +
            ",\"a long note that takes room in the clips table, row " + std::to_string(i) +
            "\"\n";
  }
  return text;
}

TEST(FullDisk, IngestFailsClearlyAndKeepsWhatWasThere) {
  if (std::system("unshare -rm true 2>/dev/null") != 0) {
    GTEST_SKIP() << "user namespaces are not available on this machine";
  }
  TempDir dir;
  WriteFile(dir / "small.csv", List(100, "a"));
  WriteFile(dir / "big.csv", List(30000, "b"));
  const auto mnt = dir / "disk";
  std::filesystem::create_directories(mnt);
  const std::string bin = DoasidoBin().string();
  const std::string db = (mnt / "d.db").string();
  // Everything on the tiny disk happens inside the namespace; the database
  // is copied out at the end for checking.
  const std::string script =
      "set -u; mount -t tmpfs -o size=600k tmpfs '" + mnt.string() + "' || exit 90; " +
      "'" + bin + "' init --db '" + db + "' --pipeline noop >/dev/null || exit 91; " +
      "'" + bin + "' ingest --db '" + db + "' '" + (dir / "small.csv").string() +
      "' > '" + (dir / "small.out").string() + "' 2>&1 || exit 92; " +
      "'" + bin + "' ingest --db '" + db + "' '" + (dir / "big.csv").string() + "' > '" +
      (dir / "big.out").string() + "' 2>&1; echo \\$? > '" + (dir / "big.rc").string() + "'; " +
      "'" + bin + "' --log-level error run --db '" + db + "' > '" + (dir / "run.out").string() +
      "' 2>&1; echo \\$? > '" + (dir / "run.rc").string() + "'; " +
      "cp '" + db + "' '" + (dir / "copy.db").string() + "'; " +
      "[ -f '" + db + "-wal' ] && cp '" + db + "-wal' '" + (dir / "copy.db-wal").string() + "'; " +
      "exit 0";
  const int rc = std::system(("unshare -rm sh -c \"" + script + "\"").c_str());
  ASSERT_EQ(rc, 0) << "namespace script failed with " << rc;

  const std::string big_out = testing::ReadFile(dir / "big.out");
  EXPECT_NE(testing::ReadFile(dir / "big.rc"), "0\n") << big_out;
  EXPECT_NE(big_out.find("disk_full"), std::string::npos) << big_out;
  EXPECT_NE(big_out.find("d.db"), std::string::npos) << "error must name the database file: "
                                                     << big_out;
  EXPECT_NE(big_out.find("big.csv"), std::string::npos) << "error must name the list: " << big_out;

  Database check(dir / "copy.db");
  // The first list is whole; of the second, only complete batches (none
  // here: it did not fit) and no partial rows.
  EXPECT_EQ(check.CountClips(), 100);
  const auto s = check.Summary();
  EXPECT_EQ(s.pending + s.done + s.running + s.failed, 100);
}

}  // namespace
}  // namespace doasido
