#pragma once
// OpenNI2 input: a live depth camera (PrimeSense/Asus Xtion through Debian's OpenNI2 drivers; Kinect
// v1 with the libfreenect OpenNI2 driver) or the playback of an .oni recording, frame by frame.
// OpenNI2 is optional at build time (CMake VOXFUSE_OPENNI2); without it every open throws IoError.

#include <memory>
#include <string>
#include <vector>

#include "voxfuse/io/ImageSource.h"

namespace voxfuse {

class OpenNISource : public ImageSource {
public:
    // True when this build has OpenNI2.
    static bool available();

    // Plays an .oni recording (OpenNI2's own, or OpenNI 1.x, as the Kinect-era recordings are) with
    // manual stepping: every recorded depth frame is delivered once, however slow the reader, and the
    // recording does not repeat. Frames the recorder mirrored are flipped back. Throws IoError naming
    // the file: missing, not a recording OpenNI2 can play, no depth stream, unsupported pixel format.
    static std::unique_ptr<OpenNISource> openFile(const std::string& path, const SourceOptions& options = {});

    // Opens a live camera: the first one found when `uri` is empty, else the one with that URI (see
    // deviceUris()), with 640x480 depth and colour at 30 Hz where offered, mirroring off and depth
    // registered to colour where the device supports it. Throws IoError when OpenNI2 cannot start,
    // no camera is connected, or it cannot stream depth.
    static std::unique_ptr<OpenNISource> openDevice(const std::string& uri = "", const SourceOptions& options = {});

    // The URIs of the connected cameras (empty without OpenNI2 or without cameras).
    static std::vector<std::string> deviceUris();

    ~OpenNISource() override;
    OpenNISource(const OpenNISource&) = delete;
    OpenNISource& operator=(const OpenNISource&) = delete;

    // options.calib_path if given (its image sizes must match the streams), else one calibration for
    // depth and colour when depth is registered to colour: intrinsics from the colour stream's field
    // of view, or Kinect v1 defaults (f 525 at 640x480) when the stream does not report one, depth in
    // millimetres. Unregistered depth gets intrinsics from its own field of view.
    const RGBDCalib& calib() const override;
    // Each depth frame with the colour frame nearest to it in time (colour empty when the device has
    // no colour stream). A frame that cannot be read throws IoError naming the file or device and the
    // frame; the next call moves on. A live camera that delivers nothing for several seconds throws
    // IoError; a recording that stalls ends after that IoError.
    bool next(RGBDFrame& frame) override;
    // Depth frames in a recording; -1 for a live camera.
    int frameCount() const override;
    std::string description() const override;
    bool isLive() const override;

private:
    struct Impl;  // OpenNI2 lives in the .cpp only
    explicit OpenNISource(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

}  // namespace voxfuse
