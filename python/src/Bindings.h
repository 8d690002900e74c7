#pragma once
// The parts of the _voxfuse extension module, each binding one area of the library.

#include <pybind11/pybind11.h>

#include "voxfuse/objects/RGBDCalib.h"

namespace voxfuse::python {

void bindErrors(pybind11::module_& m);
void bindCalibration(pybind11::module_& m);
void bindSources(pybind11::module_& m);
void bindMapOutputs(pybind11::module_& m);
void bindPipeline(pybind11::module_& m);
void bindTrajectory(pybind11::module_& m);

// Metres per raw depth unit of an affine calibration without offset; ConfigError otherwise (Calibration.cpp).
float metresPerRawUnit(const RGBDCalib& calib);

}  // namespace voxfuse::python
