// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/io/vehicle_data.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>

#include "oefmt/io/dataset.h"

namespace oefmt {
namespace {

// Calls `row` with the numbers of every line that is not blank or a comment; each must have
// `columns` of them (strtod: "inf" is read too). Stamps (column 0) must increase.
void readTable(const std::string& path, std::size_t columns, const char* layout,
               const std::function<void(const std::vector<double>&, const std::string&)>& row) {
  std::ifstream in(path);
  if (!in) throw DatasetError("cannot open '" + path + "'");
  std::string line;
  int number = 0;
  double previous = -INFINITY;
  std::vector<double> values;
  while (std::getline(in, line)) {
    ++number;
    const std::string where = "'" + path + "' line " + std::to_string(number);
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    values.clear();
    const char* cursor = line.c_str();
    while (true) {
      while (*cursor == ' ' || *cursor == '\t' || *cursor == '\r' || *cursor == ',') ++cursor;
      if (*cursor == '\0') break;
      char* end = nullptr;
      errno = 0;
      const double value = std::strtod(cursor, &end);
      if (end == cursor || std::isnan(value)) {
        throw DatasetError(where + ": expected " + std::to_string(columns) + " numbers '" + layout + "'");
      }
      values.push_back(value);
      cursor = end;
    }
    if (values.size() != columns) {
      throw DatasetError(where + ": expected " + std::to_string(columns) + " numbers '" + layout + "', found " +
                         std::to_string(values.size()));
    }
    if (!std::isfinite(values[0]) || !(values[0] > previous)) {
      throw DatasetError(where + ": the stamp must be finite and after the previous line's");
    }
    previous = values[0];
    row(values, where);
  }
}

std::FILE* openForWriting(const std::string& path, const std::vector<std::string>& header) {
  std::FILE* file = std::fopen(path.c_str(), "w");
  if (!file) throw DatasetError("cannot write '" + path + "'");
  for (const std::string& line : header) std::fprintf(file, "# %s\n", line.c_str());
  return file;
}

void close(std::FILE* file, const std::string& path) {
  const bool ok = std::ferror(file) == 0;
  if (std::fclose(file) != 0 || !ok) throw DatasetError("cannot write '" + path + "'");
}

}  // namespace

std::optional<RangeSample> rangeAt(const std::vector<RangeSample>& readings, double stamp, double tolerance) {
  const auto after = std::lower_bound(readings.begin(), readings.end(), stamp,
                                      [](const RangeSample& r, double t) { return r.stamp < t; });
  std::optional<RangeSample> nearest;
  if (after != readings.end()) nearest = *after;
  if (after != readings.begin() && (!nearest || stamp - (after - 1)->stamp < nearest->stamp - stamp)) {
    nearest = *(after - 1);
  }
  if (!nearest || !(std::fabs(nearest->stamp - stamp) <= tolerance)) return std::nullopt;
  return nearest;
}

std::optional<double> verticalRange(const std::vector<RangeSample>& readings, double stamp, double tolerance,
                                    const std::optional<CameraTilt>& tilt) {
  const std::optional<RangeSample> reading = rangeAt(readings, stamp, tolerance);
  if (!reading || !std::isfinite(reading->range)) return std::nullopt;
  return reading->range * (tilt ? std::cos(tilt->roll) * std::cos(tilt->pitch) : 1.0);
}

std::vector<ImuSample> readImuFile(const std::string& path) {
  std::vector<ImuSample> samples;
  readTable(path, 11, "t qx qy qz qw wx wy wz ax ay az", [&](const std::vector<double>& v, const std::string& where) {
    for (const double value : v) {
      if (!std::isfinite(value)) throw DatasetError(where + ": every value must be finite");
    }
    ImuSample sample;
    sample.stamp = v[0];
    sample.orientation = Eigen::Quaterniond(v[4], v[1], v[2], v[3]);
    if (!(sample.orientation.norm() > 1e-6)) throw DatasetError(where + ": the orientation is a zero quaternion");
    sample.orientation.normalize();
    sample.angular_velocity = Eigen::Vector3d(v[5], v[6], v[7]);
    sample.linear_acceleration = Eigen::Vector3d(v[8], v[9], v[10]);
    samples.push_back(sample);
  });
  return samples;
}

void writeImuFile(const std::string& path, const std::vector<ImuSample>& samples,
                  const std::vector<std::string>& header) {
  std::FILE* file = openForWriting(path, header);
  for (const ImuSample& s : samples) {
    const Eigen::Quaterniond& q = s.orientation;
    std::fprintf(file, "%.6f %.9f %.9f %.9f %.9f %.6f %.6f %.6f %.5f %.5f %.5f\n", s.stamp, q.x(), q.y(), q.z(),
                 q.w(), s.angular_velocity.x(), s.angular_velocity.y(), s.angular_velocity.z(),
                 s.linear_acceleration.x(), s.linear_acceleration.y(), s.linear_acceleration.z());
  }
  close(file, path);
}

std::vector<RangeSample> readRangeFile(const std::string& path) {
  std::vector<RangeSample> samples;
  readTable(path, 2, "t range", [&](const std::vector<double>& v, const std::string& where) {
    if (!(v[1] > 0.0)) throw DatasetError(where + ": a range must be > 0 (inf: no return)");
    samples.push_back({v[0], v[1]});
  });
  return samples;
}

void writeRangeFile(const std::string& path, const std::vector<RangeSample>& samples,
                    const std::vector<std::string>& header) {
  std::FILE* file = openForWriting(path, header);
  for (const RangeSample& s : samples) {
    if (std::isinf(s.range)) {
      std::fprintf(file, "%.6f inf\n", s.stamp);
    } else {
      std::fprintf(file, "%.6f %.4f\n", s.stamp, s.range);
    }
  }
  close(file, path);
}

}  // namespace oefmt
