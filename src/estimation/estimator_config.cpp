// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/estimation/estimator_config.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iterator>
#include <set>
#include <sstream>
#include <vector>

#include "oefmt/error.h"
#include "oefmt/io/yaml_map.h"

namespace oefmt {
namespace {

bool finiteIn(double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; }

// ---- reading one value -------------------------------------------------------------------

[[noreturn]] void badValue(const std::string& key, const std::string& expected) {
  throw InputError("invalid parameter '" + key + "': expected " + expected);
}

std::string trimmed(const std::string& s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

// Values are text (parseYaml keeps scalars as written); numbers, integers, booleans and words
// are told apart here, with the key in the message.
const std::string& scalarOf(const YamlNode& node, const std::string& key, const std::string& expected) {
  if (node.is_map) badValue(key, expected + ", not a map");
  return node.scalar;
}

double readDouble(const YamlNode& node, const std::string& key) {
  bool out_of_range = false;
  const std::optional<double> v = yamlNumber(trimmed(scalarOf(node, key, "a number")), &out_of_range);
  if (!v || out_of_range) badValue(key, "a number");
  return *v;
}

int readInt(const YamlNode& node, const std::string& key) {
  const double v = readDouble(node, key);
  if (!(std::fabs(v) < 1e9) || v != std::floor(v)) badValue(key, "an integer");
  return static_cast<int>(v);
}

bool readBool(const YamlNode& node, const std::string& key) {
  const std::string text = trimmed(scalarOf(node, key, "true or false"));
  if (text == "true" || text == "True" || text == "TRUE" || text == "yes" || text == "on" || text == "1") return true;
  if (text == "false" || text == "False" || text == "FALSE" || text == "no" || text == "off" || text == "0") return false;
  badValue(key, "true or false");
}

std::string readString(const YamlNode& node, const std::string& key) {
  return trimmed(scalarOf(node, key, "a word"));
}

// One of an enum's words (its name table), the message listing them.
template <typename T, std::size_t N>
T readWord(const YamlNode& node, const std::string& key, const EnumName<T> (&names)[N]) {
  const std::optional<T> value = findEnum(names, readString(node, key));
  if (!value) badValue(key, wordList(enumNames(names)));
  return *value;
}

// ---- writing one value -------------------------------------------------------------------

// A double that both OpenCV and PyYAML read back as a number (YAML 1.1 wants a dot).
std::string formatDouble(double v) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.10g", v);
  std::string s = buffer;
  if (s.find_first_of(".ein") == std::string::npos) return s + ".0";
  const auto e = s.find('e');
  if (e != std::string::npos && s.find('.') == std::string::npos) s.insert(e, ".0");
  return s;
}

// ---- the parameter table -----------------------------------------------------------------

struct Field {
  std::string key;  // within its section
  std::function<void(const YamlNode&, const std::string&)> read;
  std::function<std::string()> write;
};

struct Section {
  std::string name;  // "" for the top level
  std::vector<Field> fields;
  std::function<void()> validate;
};

Field number(const std::string& key, double& target) {
  return {key, [&target](const YamlNode& n, const std::string& k) { target = readDouble(n, k); },
          [&target] { return formatDouble(target); }};
}
Field integer(const std::string& key, int& target) {
  return {key, [&target](const YamlNode& n, const std::string& k) { target = readInt(n, k); },
          [&target] { return std::to_string(target); }};
}
Field boolean(const std::string& key, bool& target) {
  return {key, [&target](const YamlNode& n, const std::string& k) { target = readBool(n, k); },
          [&target] { return std::string(target ? "true" : "false"); }};
}

template <typename T, std::size_t N>
Field word(const std::string& key, T& target, const EnumName<T> (&names)[N]) {
  return {key, [&target, &names](const YamlNode& n, const std::string& k) { target = readWord(n, k, names); },
          [&target, &names] { return std::string(enumName(names, target)); }};
}

std::vector<Section> sections(EstimatorConfig& c) {
  std::vector<Section> all;
  all.push_back({"",
                 {word("mode", c.mode, kEstimatorModeNames),
                  number("altitude", c.altitude), number("fx", c.fx),
                  boolean("parallel_registrations", c.parallel_registrations)},
                 [&c] {
                   requireParameter(std::isfinite(c.altitude) && c.altitude >= 0.0, "altitude",
                                    "must be >= 0 m (0 = unknown)");
                   requireParameter(std::isfinite(c.fx) && c.fx >= 0.0, "fx", "must be >= 0 px (0 = size)");
                 }});
  RegistrationConfig& r = c.registration;
  all.push_back({"registration",
                 {integer("size", r.size), number("taper_fraction", r.taper_fraction),
                  number("logpolar_radius_fraction", r.logpolar_radius_fraction),
                  number("polar_radius_fraction", r.polar_radius_fraction),
                  integer("block_radius", r.block_radius),
                  number("energy_smoothing_sigma", r.energy_smoothing_sigma),
                  boolean("resolve_half_turn", r.resolve_half_turn),
                  number("min_texture", r.min_texture), number("min_confidence", r.min_confidence),
                  integer("rotation_zoom_candidates", r.rotation_zoom_candidates),
                  number("identity_warp_px", r.identity_warp_px),
                  boolean("noise_weighting", r.noise_weighting),
                  word("fft_planning", r.fft_planning, kFftPlanningNames)},
                 [&r] { r.validate(); }});
  MatchingConfig& m = c.matching;
  all.push_back({"matching",
                 {integer("stretch_steps", m.stretch_steps),
                  number("stretch_key_12", m.stretch_key_12),
                  number("stretch_key_02", m.stretch_key_02),
                  number("stretch_init_window", m.stretch_init_window),
                  number("max_normalised_error", m.max_normalised_error),
                  number("smoothing_sigma", m.smoothing_sigma),
                  number("stretch_sigma_floor", m.stretch_sigma_floor),
                  number("shift_range", m.shift_range), number("shift_step", m.shift_step),
                  number("shift_sigma_floor", m.shift_sigma_floor),
                  number("min_peak_bins", m.min_peak_bins), integer("skip_bins", m.skip_bins)},
                 [&m] { m.validate(); }});
  LocalOptimizerOptions& o = c.optimizer;
  all.push_back({"optimizer",
                 {integer("max_iterations", o.max_iterations),
                  word("robust_loss", o.robust_loss, kRobustLossNames),
                  number("loss_scale", o.loss_scale),
                  number("loop_translation_sigma", o.loop_translation_sigma),
                  number("loop_translation_sigma_relative", o.loop_translation_sigma_relative),
                  number("loop_rotation_sigma", o.loop_rotation_sigma),
                  number("loop_log_zoom_sigma", o.loop_log_zoom_sigma),
                  number("function_tolerance", o.function_tolerance)},
                 [&o] { o.validate(); }});
  TrackingConfig& t = c.tracking;
  all.push_back({"tracking",
                 {number("layer_gate", t.layer_gate), number("layer_search", t.layer_search),
                  number("layer_min_fraction", t.layer_min_fraction),
                  number("steady_layer_min_fraction", t.steady_layer_min_fraction),
                  integer("max_failed_frames", t.max_failed_frames),
                  boolean("predict_failed_frames", t.predict_failed_frames),
                  number("prediction_sigma", t.prediction_sigma),
                  number("motion_prior_sigma", t.motion_prior_sigma),
                  number("max_acceleration", t.max_acceleration),
                  number("assumed_altitude", t.assumed_altitude)},
                 [&t] { t.validate(); }});
  UncertaintyConfig& u = c.uncertainty;
  all.push_back({"uncertainty",
                 {number("rotation_scale", u.rotation_scale),
                  number("log_zoom_scale", u.log_zoom_scale), number("shift_scale", u.shift_scale),
                  number("direction_scale", u.direction_scale)},
                 [&u] { u.validate(); }});
  EfmtConfig& e = c.efmt;
  all.push_back({"efmt",
                 {integer("zoom_samples", e.zoom_samples), number("zoom_threshold", e.zoom_threshold),
                  integer("sector_half_width", e.sector_half_width)},
                 [&e] { e.validate(); }});
  return all;
}

// Reads the fields of one map node; unknown keys are errors (a typo must not pass silently).
void readSection(const Section& section, const YamlNode& node, const std::string& prefix) {
  std::set<std::string> known;
  for (const Field& f : section.fields) known.insert(f.key);
  for (const auto& [name, child] : node.children) {
    if (prefix.empty() && child.is_map) continue;  // a section, read separately
    if (known.count(name) == 0) throw InputError("unknown parameter '" + prefix + name + "'");
  }
  for (const Field& f : section.fields) {
    const YamlNode* child = node.find(f.key);
    if (child == nullptr || child->is_null) continue;
    f.read(*child, prefix + f.key);
  }
}

void validateSection(const Section& section) {
  try {
    section.validate();
  } catch (const InputError& e) {
    if (section.name.empty()) throw;
    throw InputError(section.name + ": " + e.what());
  }
}

}  // namespace

void MatchingConfig::validate() const {
  requireParameter(stretch_steps >= 2 && stretch_steps <= 1000, "stretch_steps", "must be in [2, 1000]");
  requireParameter(finiteIn(stretch_key_12, 1.0, 100.0), "stretch_key_12", "must be in [1, 100] per mille");
  requireParameter(finiteIn(stretch_key_02, 1.0, 100.0), "stretch_key_02", "must be in [1, 100] per mille");
  requireParameter(finiteIn(stretch_init_window, 0.05, 10.0), "stretch_init_window", "must be in [0.05, 10]");
  requireParameter(finiteIn(max_normalised_error, 0.01, 1.0), "max_normalised_error", "must be in [0.01, 1]");
  requireParameter(finiteIn(smoothing_sigma, 0.0, 10.0), "smoothing_sigma", "must be in [0, 10] bins");
  requireParameter(finiteIn(stretch_sigma_floor, 1e-6, 1.0), "stretch_sigma_floor", "must be in [1e-6, 1]");
  requireParameter(finiteIn(shift_range, 1.0, 200.0), "shift_range", "must be in [1, 200] bins");
  requireParameter(finiteIn(shift_step, 0.001, 0.5), "shift_step", "must be in [0.001, 0.5] bins");
  requireParameter(finiteIn(shift_sigma_floor, 1e-6, 10.0), "shift_sigma_floor", "must be in [1e-6, 10] bins");
  requireParameter(finiteIn(min_peak_bins, 0.0, 100.0), "min_peak_bins", "must be in [0, 100] bins");
  requireParameter(skip_bins >= 0 && skip_bins <= 100, "skip_bins", "must be in [0, 100] bins");
}

void TrackingConfig::validate() const {
  requireParameter(finiteIn(layer_gate, 0.001, 1.0), "layer_gate", "must be in [0.001, 1]");
  requireParameter(finiteIn(layer_search, 0.001, 1.0), "layer_search", "must be in [0.001, 1]");
  requireParameter(finiteIn(layer_min_fraction, 0.0, 1.0), "layer_min_fraction", "must be in [0, 1]");
  requireParameter(finiteIn(steady_layer_min_fraction, 0.0, 1.0), "steady_layer_min_fraction", "must be in [0, 1]");
  requireParameter(max_failed_frames >= 0 && max_failed_frames <= 1000, "max_failed_frames", "must be in [0, 1000]");
  requireParameter(finiteIn(prediction_sigma, 0.0, 100.0), "prediction_sigma", "must be in [0, 100]");
  requireParameter(finiteIn(motion_prior_sigma, 0.0, 100.0), "motion_prior_sigma", "must be in [0, 100]");
  requireParameter(finiteIn(max_acceleration, 0.01, 1000.0), "max_acceleration", "must be in [0.01, 1000] m/s^2");
  requireParameter(finiteIn(assumed_altitude, 0.01, 1e5), "assumed_altitude", "must be in [0.01, 1e5] m");
}

void UncertaintyConfig::validate() const {
  requireParameter(finiteIn(rotation_scale, 1e-4, 100.0), "rotation_scale", "must be in [1e-4, 100]");
  requireParameter(finiteIn(log_zoom_scale, 1e-4, 100.0), "log_zoom_scale", "must be in [1e-4, 100]");
  requireParameter(finiteIn(shift_scale, 1e-4, 100.0), "shift_scale", "must be in [1e-4, 100]");
  requireParameter(finiteIn(direction_scale, 1e-4, 100.0), "direction_scale", "must be in [1e-4, 100]");
}

void EfmtConfig::validate() const {
  requireParameter(zoom_samples >= 1 && zoom_samples <= 50, "zoom_samples", "must be in [1, 50]");
  requireParameter(finiteIn(zoom_threshold, 0.0, 1.0), "zoom_threshold", "must be in [0, 1]");
  requireParameter(sector_half_width >= 0 && sector_half_width <= 64, "sector_half_width", "must be in [0, 64]");
}

void EstimatorConfig::validate() const {
  EstimatorConfig copy = *this;
  for (const Section& section : sections(copy)) validateSection(section);
}

EstimatorConfig parseConfig(const YamlNode& root, const std::string& source) {
  EstimatorConfig config;
  try {
    if (!root.is_map) throw InputError("expected a map of parameters at the top level");
    const std::vector<Section> all = sections(config);
    std::set<std::string> section_names;
    for (const Section& s : all) section_names.insert(s.name);
    for (const auto& [name, child] : root.children) {
      if (child.is_map && section_names.count(name) == 0) {
        throw InputError("unknown parameter section '" + name + "'");
      }
    }
    for (const Section& s : all) {
      if (s.name.empty()) {
        readSection(s, root, "");
        continue;
      }
      const YamlNode* node = root.find(s.name);
      if (node == nullptr || node->is_null) continue;
      if (!node->is_map) throw InputError("parameter section '" + s.name + "' must be a map");
      readSection(s, *node, s.name + ".");
    }
    for (const Section& s : all) validateSection(s);
  } catch (const InputError& e) {
    throw InputError(source + ": " + e.what());
  }
  return config;
}

EstimatorConfig loadConfig(const std::string& yaml_path) {
  std::ifstream in(yaml_path, std::ios::binary);
  if (!in) throw InputError("cannot open configuration file '" + yaml_path + "'");
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) throw InputError("cannot read configuration file '" + yaml_path + "'");
  return parseConfig(parseYaml(text, "configuration file '" + yaml_path + "'"), yaml_path);
}

std::string configToYaml(const EstimatorConfig& config) {
  EstimatorConfig copy = config;
  std::ostringstream out;
  out << "%YAML 1.0\n---\n";
  for (const Section& s : sections(copy)) {
    const std::string indent = s.name.empty() ? "" : "  ";
    if (!s.name.empty()) out << s.name << ":\n";
    for (const Field& f : s.fields) out << indent << f.key << ": " << f.write() << "\n";
  }
  return out.str();
}

}  // namespace oefmt
