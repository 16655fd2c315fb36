// SPDX-License-Identifier: GPL-3.0-or-later
// doc/diagnostics.md is what the diagnostics column table gives (oefmt_offline
// --diagnostics-columns), and every line the table writes has a value for every column.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <set>
#include <string>

#include "diagnostics_csv.h"
#include "support/package_files.h"

namespace oefmt {
namespace {

TEST(DiagnosticsDoc, DocDiagnosticsMdIsTheGeneratedOne) {
  EXPECT_EQ(test::readFile(test::packageRoot() / "doc" / "diagnostics.md"), diagnosticsMarkdown())
      << "doc/diagnostics.md is not what the column table gives: regenerate it with\n"
         "  rosrun oefmt oefmt_offline --diagnostics-columns > doc/diagnostics.md";
}

TEST(DiagnosticsDoc, ColumnsAreNamedOnceAndDescribed) {
  std::set<std::string> names;
  for (const DiagnosticsColumn& c : diagnosticsColumns()) {
    EXPECT_TRUE(names.insert(c.name).second) << c.name << " twice";
    EXPECT_GT(std::string(c.meaning).size(), 10u) << c.name;
    EXPECT_EQ(std::string(c.name).find(','), std::string::npos) << c.name;
  }
}

TEST(DiagnosticsDoc, EveryLineHasOneValuePerColumn) {
  Estimate e;
  e.frame_index = 12;
  e.stamp = 3.5;
  e.state = TrackingState::kPredicted;
  e.pose.x = -1.25;
  e.length_spread = 0.5;
  const std::string header = diagnosticsCsvHeader(), line = diagnosticsCsvLine(e);
  ASSERT_EQ(header.back(), '\n');
  ASSERT_EQ(line.back(), '\n');
  EXPECT_EQ(std::count(line.begin(), line.end(), ','), std::count(header.begin(), header.end(), ','));
  EXPECT_EQ(line.rfind("12,3.500000000,predicted,0,", 0), 0u) << line;
  EXPECT_NE(line.find(",-1.250000,"), std::string::npos) << line;
  // A diverged pose is written in full, not cut at a buffer's end.
  e.pose.y = 1e120;
  char full[256];
  std::snprintf(full, sizeof(full), ",%.6f,", e.pose.y);
  EXPECT_NE(diagnosticsCsvLine(e).find(full), std::string::npos);
}

}  // namespace
}  // namespace oefmt
