// SPDX-License-Identifier: GPL-3.0-or-later
// A one-line progress bar for the command-line tools, drawn only on a terminal.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>

namespace oefmt {
namespace tools {

class ProgressBar {
 public:
  /// Draws on `stream` only when it is a terminal (no escape noise in logs and pipes).
  ProgressBar(std::string label, std::size_t total, std::FILE* stream = stderr);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  /// `done` items of `total` are finished; redraws at most 10 times a second (and at the end).
  void update(std::size_t done);
  /// Ends the line (also done by the destructor).
  void finish();
  bool enabled() const { return enabled_; }

 private:
  void draw(std::size_t done);

  std::string label_;
  std::size_t total_;
  std::FILE* stream_;
  bool enabled_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
};

}  // namespace tools
}  // namespace oefmt
