// SPDX-License-Identifier: GPL-3.0-or-later
// The per-frame diagnostics CSV of oefmt_offline --diagnostics: one table of its columns (name,
// unit, meaning, value) that writes the header, every line and doc/diagnostics.md, so that the
// file and its documentation cannot drift apart (a test compares the document with the table).
#pragma once

#include <string>
#include <vector>

#include "oefmt/estimation/estimator.h"

namespace oefmt {

struct DiagnosticsColumn {
  const char* name;
  const char* unit;     ///< "" for a count, a flag or a name
  const char* meaning;
  std::string (*value)(const Estimate&);
};

/// The columns in file order.
const std::vector<DiagnosticsColumn>& diagnosticsColumns();

/// The header line (column names), with its newline.
std::string diagnosticsCsvHeader();

/// One frame's line, with its newline.
std::string diagnosticsCsvLine(const Estimate& estimate);

/// doc/diagnostics.md (oefmt_offline --diagnostics-columns prints it).
std::string diagnosticsMarkdown();

}  // namespace oefmt
