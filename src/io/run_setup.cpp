// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/io/run_setup.h"

#include <cmath>

#include "oefmt/io/undistortion.h"

namespace oefmt {

std::optional<ChosenCamera> chooseCamera(const CameraSources& sources, cv::Size image_size) {
  std::optional<ChosenCamera> chosen;
  if (sources.override_fx > 0.0) {
    CameraParameters camera = pinholeCamera(sources.override_fx, image_size);
    if (sources.calibration) {
      const Intrinsics& k = sources.calibration->intrinsics;
      if (k.width > 0 && k.height > 0) {
        const Intrinsics mapped = intrinsicsForImageSize(k, image_size);
        camera.intrinsics.cx = mapped.cx;
        camera.intrinsics.cy = mapped.cy;
      }
      camera.distortion = sources.calibration->distortion;
    }
    chosen = ChosenCamera{camera, sources.override_source};
  } else if (sources.calibration) {
    chosen = ChosenCamera{*sources.calibration, sources.calibration_source};
  } else if (sources.camera_fx > 0.0) {
    chosen = ChosenCamera{pinholeCamera(sources.camera_fx, image_size), "camera_fx"};
  }
  if (chosen && !sources.undistort) chosen->camera.distortion = Distortion{};
  return chosen;
}

double chooseInitialAltitude(std::optional<double> for_this_run, double configured) {
  if (for_this_run && std::isfinite(*for_this_run) && *for_this_run > 0.0) return *for_this_run;
  return configured;
}

}  // namespace oefmt
