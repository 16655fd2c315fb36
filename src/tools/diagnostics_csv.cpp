// SPDX-License-Identifier: GPL-3.0-or-later
#include "diagnostics_csv.h"

#include <cstdio>

namespace oefmt {
namespace {

// As long as the value needs: a diverged pose's %.6f can run to hundreds of digits, and a
// truncated number would be silent garbage in the file.
template <typename... Args>
std::string format(const char* pattern, Args... args) {
  const int length = std::snprintf(nullptr, 0, pattern, args...);
  if (length <= 0) return std::string();
  std::string text(static_cast<std::size_t>(length), '\0');
  std::snprintf(text.data(), text.size() + 1, pattern, args...);
  return text;
}

const PairRegistration& pair12(const Estimate& e) { return e.registration12; }

}  // namespace

const std::vector<DiagnosticsColumn>& diagnosticsColumns() {
  static const std::vector<DiagnosticsColumn> columns = {
      {"frame", "", "0-based index of the frame in the input",
       [](const Estimate& e) { return format("%zu", e.frame_index); }},
      {"stamp", "s", "the frame's time stamp", [](const Estimate& e) { return format("%.9f", e.stamp); }},
      {"state", "",
       "started (the origin), tracking (registered), predicted (extrapolated with the last motion at the "
       "last steps' median turn and zoom), held (the pose kept), restarted (the window starts again "
       "from this frame)",
       [](const Estimate& e) { return std::string(toString(e.state)); }},
      {"degraded", "", "1 when the pose did not come from a confident registration of this frame",
       [](const Estimate& e) { return format("%d", e.degraded ? 1 : 0); }},
      {"turn_predicted", "",
       "1 when the measured turn was an outlier of the last turns' deviations from their predictions "
       "and the predicted turn was integrated",
       [](const Estimate& e) { return format("%d", e.turn_predicted ? 1 : 0); }},
      {"zoom_predicted", "",
       "1 when the measured zoom was an outlier of the last zooms' deviations from their predictions "
       "and the predicted zoom was integrated",
       [](const Estimate& e) { return format("%d", e.zoom_predicted ? 1 : 0); }},
      {"alias_left", "",
       "1 when the track had started on a reading a rival matched as well and this pair's unrivalled "
       "highest translation peak, outside the predicted window, restarted the window from it",
       [](const Estimate& e) { return format("%d", e.alias_left ? 1 : 0); }},
      {"theta_rad", "rad", "pair 1-2's registered rotation (counter-clockwise on screen)",
       [](const Estimate& e) { return format("%.8f", pair12(e).rotation); }},
      {"zoom", "", "pair 1-2's registered zoom (the newer frame looks this much larger)",
       [](const Estimate& e) { return format("%.8f", pair12(e).zoom); }},
      {"phi_rad", "rad", "direction of pair 1-2's translation peak (image axes, y down)",
       [](const Estimate& e) { return format("%.8f", pair12(e).direction); }},
      {"rho_px", "px", "length of pair 1-2's translation peak (working image pixels)",
       [](const Estimate& e) { return format("%.5f", pair12(e).shift); }},
      {"confidence", "", "pair 1-2's registration confidence, 0 (unusable) to 1",
       [](const Estimate& e) { return format("%.4f", pair12(e).confidence); }},
      {"rival_ratio", "",
       "height of the strongest rival of pair 1-2's translation peak relative to it, each divided by the "
       "frames' overlap at its shift (0: none; near 1: an equally good reading, e.g. a periodic texture's alias)",
       [](const Estimate& e) { return format("%.4f", pair12(e).rival_ratio); }},
      {"sigma_theta_rad", "rad", "sigma of theta_rad from the peak's width",
       [](const Estimate& e) { return format("%.8f", pair12(e).rotation_sigma); }},
      {"refined_theta_rad", "rad",
       "pair 1-2's rotation as the zoom refinement read it, or as the image blocks read it where the "
       "refinement had not settled (0: not refined)",
       [](const Estimate& e) { return format("%.8f", pair12(e).refined_rotation); }},
      {"sigma_refined_theta_rad", "rad",
       "sigma of refined_theta_rad from the refinement's normal equations, and the blocks' scatter where "
       "they were read (0: none; uncertainty.refined_rotation_scale calibrates it)",
       [](const Estimate& e) { return format("%.8f", pair12(e).refined_rotation_sigma); }},
      {"motion_blocks", "",
       "image blocks whose shifts read pair 1-2's rotation where its zoom refinement had not settled "
       "(0: the refinement settled, or no block followed the pair)",
       [](const Estimate& e) { return format("%d", pair12(e).motion_blocks); }},
      {"sigma_log_zoom", "", "sigma of ln(zoom) from the peak's width",
       [](const Estimate& e) { return format("%.8f", pair12(e).log_zoom_sigma); }},
      {"sigma_refined_log_zoom", "",
       "sigma of the refined ln(zoom) from the refinement's normal equations (0: the zoom was not refined; "
       "uncertainty.refined_log_zoom_scale calibrates it)",
       [](const Estimate& e) { return format("%.8f", pair12(e).refined_log_zoom_sigma); }},
      {"sigma_slope_log_zoom", "",
       "the part of the slope's ln(zoom) that pair 1-2's stretch read and its zoom does not hold, added to the "
       "refined zoom's sigma (0: the whole correction was taken, or none was read)",
       [](const Estimate& e) { return format("%.8f", pair12(e).slope_log_zoom_sigma); }},
      {"sigma_phi_rad", "rad", "sigma of phi_rad from the peak's width",
       [](const Estimate& e) { return format("%.8f", pair12(e).direction_sigma); }},
      {"sigma_rho_px", "px", "sigma of rho_px from the peak's width",
       [](const Estimate& e) { return format("%.5f", pair12(e).shift_sigma); }},
      {"pmt12", "", "stretch of pair 1-2's translation energy against pair 0-1's (about 1 at steady speed)",
       [](const Estimate& e) { return format("%.6f", e.pmt12.value); }},
      {"pmt12_sigma", "", "sigma of ln(pmt12); 0 when no stretch was matched",
       [](const Estimate& e) { return format("%.6f", e.pmt12.sigma); }},
      {"pmt02", "", "stretch of pair 0-2's translation energy against pair 0-1's (about 2 at steady speed)",
       [](const Estimate& e) { return format("%.6f", e.pmt02.value); }},
      {"pmt02_sigma", "", "sigma of ln(pmt02); 0 when no stretch was matched",
       [](const Estimate& e) { return format("%.6f", e.pmt02.sigma); }},
      {"pms12_bins", "bins", "shift of pair 1-2's zoom energy against pair 0-1's (about 0 at a steady climb rate)",
       [](const Estimate& e) { return format("%.4f", e.pms12.value); }},
      {"pms12_sigma", "bins", "sigma of pms12_bins",
       [](const Estimate& e) { return format("%.4f", e.pms12.sigma); }},
      {"pms02_bins", "bins", "shift of pair 0-2's zoom energy against pair 0-1's (reported only: not observed)",
       [](const Estimate& e) { return format("%.4f", e.pms02.value); }},
      {"pms02_sigma", "bins", "sigma of pms02_bins",
       [](const Estimate& e) { return format("%.4f", e.pms02.sigma); }},
      {"lambda_t12", "", "length of the integrated step over the previous one",
       [](const Estimate& e) { return format("%.6f", e.lambda_t12); }},
      {"lambda_t02", "", "length of the optimized pair 0-2 over the previous step (0 without a loop)",
       [](const Estimate& e) { return format("%.6f", e.lambda_t02); }},
      {"length_spread_px", "px",
       "distance of the step's other length readings (PMT stretch, highest peak) from the integrated "
       "length, added to the pose's covariance along the step; 0 when they agree",
       [](const Estimate& e) { return format("%.4f", e.length_spread); }},
      {"length_source", "",
       "which reading gave the integrated step's length: peak (the pair's translation peak), "
       "window_peak (the peak where the prediction pointed; another layer's was higher), energy_peak "
       "(the followed layer's peak in the translation energy vector), layer_ratio (a layer seen in both "
       "pairs, through its ratio), stretch (the energy vectors' pattern match), prediction (the motion "
       "so far; nothing in view read the followed layer), motion_change (a peak on the motion within "
       "the acceleration window: the speed changed), loop (the three-frame loop moved it by more than "
       "tracking.layer_gate), vouched (the ratios the layers in view held over the last steps), "
       "implausible (the reading lay beyond the acceleration window: the prediction stands); none when "
       "no step was integrated",
       [](const Estimate& e) { return std::string(toString(e.length_source)); }},
      {"vouched_length_px", "px",
       "oefmt: the step length the depth layers in view vouched for by the ratios they held over the last "
       "steps, where the step's own broke them and was replaced by it, or where the pair was too weak to "
       "register on its own and was tracked on it (degraded 1; before the ratios held, the followed "
       "layer's own peak at the predicted length); 0 = the step's own length stood",
       [](const Estimate& e) { return format("%.4f", e.vouched_length); }},
      {"plane_tilt_x_rad", "rad",
       "levelled frames: the ground plane's tilt left in the level view, its normal's component "
       "along the image's x axis (the attitude's error as the pairs' stretch read it; the zooms "
       "were corrected for it); 0 otherwise",
       [](const Estimate& e) { return format("%.6f", e.plane_tilt.x); }},
      {"plane_tilt_y_rad", "rad", "the same component along the image's y axis (down)",
       [](const Estimate& e) { return format("%.6f", e.plane_tilt.y); }},
      {"optimizer_status", "", "the three-frame loop: converged, fallback (the measurements stand) or skipped",
       [](const Estimate& e) { return std::string(toString(e.loop.status)); }},
      {"rotation_only02", "",
       "1 when pair 0-2's translation did not register and the loop took its rotation alone (its "
       "rotation and zoom peak within the gates of the rates' recent deviations)",
       [](const Estimate& e) { return format("%d", e.rotation_only02 ? 1 : 0); }},
      {"optimizer_iterations", "", "Levenberg-Marquardt iterations over all starting points",
       [](const Estimate& e) { return format("%d", e.loop.iterations); }},
      {"cost_initial", "", "the loop's cost at the winning start",
       [](const Estimate& e) { return format("%.6g", e.loop.initial_cost); }},
      {"cost_final", "", "the loop's cost at its solution",
       [](const Estimate& e) { return format("%.6g", e.loop.final_cost); }},
      {"x", "m", "position east of the first camera position (units of the initial altitude when it is unknown)",
       [](const Estimate& e) { return format("%.6f", e.pose.x); }},
      {"y", "m", "position north of the first camera position (same units)",
       [](const Estimate& e) { return format("%.6f", e.pose.y); }},
      {"z", "m", "height above the first camera position (same units)",
       [](const Estimate& e) { return format("%.6f", e.pose.z); }},
      {"yaw", "rad", "heading, counter-clockwise seen from above, 0 at the first frame",
       [](const Estimate& e) { return format("%.8f", e.pose.yaw); }},
      {"step_var_x", "m²", "variance of this frame's step along x (world frame, same units)",
       [](const Estimate& e) { return format("%.6g", e.step_covariance(0, 0)); }},
      {"step_cov_xy", "m²", "covariance of the step's x and y",
       [](const Estimate& e) { return format("%.6g", e.step_covariance(0, 1)); }},
      {"step_var_y", "m²", "variance of the step along y",
       [](const Estimate& e) { return format("%.6g", e.step_covariance(1, 1)); }},
      {"step_var_z", "m²", "variance of the step's height change",
       [](const Estimate& e) { return format("%.6g", e.step_covariance(2, 2)); }},
      {"step_var_yaw", "rad²", "variance of the step's turn",
       [](const Estimate& e) { return format("%.6g", e.step_covariance(3, 3)); }},
      {"registration_ms", "ms", "spectra and registrations of this frame (wall time)",
       [](const Estimate& e) { return format("%.3f", e.registration_ms); }},
      {"estimator_ms", "ms", "everything else: matching, optimizer, bookkeeping",
       [](const Estimate& e) { return format("%.3f", e.estimator_ms); }},
      {"total_ms", "ms", "the whole frame", [](const Estimate& e) { return format("%.3f", e.total_ms); }},
  };
  return columns;
}

std::string diagnosticsCsvHeader() {
  std::string line;
  for (const DiagnosticsColumn& c : diagnosticsColumns()) line += (line.empty() ? "" : ",") + std::string(c.name);
  return line + "\n";
}

std::string diagnosticsCsvLine(const Estimate& estimate) {
  std::string line;
  bool first = true;
  for (const DiagnosticsColumn& c : diagnosticsColumns()) {
    if (!first) line += ',';
    line += c.value(estimate);
    first = false;
  }
  return line + "\n";
}

std::string diagnosticsMarkdown() {
  std::string doc =
      "<!-- Generated by `oefmt_offline --diagnostics-columns` from the column table in the code\n"
      "     (src/tools/diagnostics_csv.cpp); a test compares this file with it. -->\n"
      "# Per-frame diagnostics\n\n"
      "`oefmt_offline --diagnostics FILE` writes one CSV line per frame, after a header line with\n"
      "these column names. Pair 1-2 is the newest frame against the previous accepted one, pair 0-1\n"
      "the step before it and pair 0-2 the loop's long pair (`doc/method.md`). Registration values\n"
      "are the raw measurement of pair 1-2; the pose and the step covariance are what was\n"
      "integrated. Values of a step that did not run (no loop, no pattern match, the first frame)\n"
      "are 0.\n\n"
      "| column | unit | meaning |\n|---|---|---|\n";
  for (const DiagnosticsColumn& c : diagnosticsColumns()) {
    doc += std::string("| `") + c.name + "` | " + c.unit + " | " + c.meaning + " |\n";
  }
  return doc;
}

}  // namespace oefmt
