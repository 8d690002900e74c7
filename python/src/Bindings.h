#pragma once
// The parts of the _voxfuse extension module, each binding one area of the library.

#include <pybind11/pybind11.h>

#include <cstdint>

#include "voxfuse/core/Image.h"
#include "voxfuse/objects/RGBDCalib.h"

namespace voxfuse::python {

void bindErrors(pybind11::module_& m);
void bindCalibration(pybind11::module_& m);
void bindSources(pybind11::module_& m);
void bindMapOutputs(pybind11::module_& m);
void bindPipeline(pybind11::module_& m);
void bindTrajectory(pybind11::module_& m);

// A depth array (uint16 raw, float32/float64 metres) and a colour array (uint8 (H, W, 3|4)) copied into
// a frame's images, checked against the calibration's image sizes (PipelineBindings.cpp). raw_scale > 0:
// uint16 depth in units of that many metres.
void copyDepth(const pybind11::handle& value, const RGBDCalib& calib, float raw_scale, Image<std::uint16_t>& out);
void copyRgb(const pybind11::handle& value, const RGBDCalib& calib, Image<Vec4u8>& out);

// Metres per raw depth unit of an affine calibration without offset; ConfigError otherwise (Calibration.cpp).
float metresPerRawUnit(const RGBDCalib& calib);

}  // namespace voxfuse::python
