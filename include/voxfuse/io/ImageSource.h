#pragma once
// The one interface every input (files, TUM folders, per-frame folders, OpenNI) implements.

#include <memory>
#include <string>
#include <vector>

#include "voxfuse/io/RGBDFrame.h"
#include "voxfuse/io/TrajectoryIO.h"
#include "voxfuse/objects/RGBDCalib.h"

namespace voxfuse {

class ImageSource {
public:
    virtual ~ImageSource() = default;

    virtual const RGBDCalib& calib() const = 0;
    // Reads the next frame into `frame`. Returns false at the end of the sequence. A frame that cannot
    // be read throws IoError (naming file, frame and reason) and is skipped: the next call moves on.
    virtual bool next(RGBDFrame& frame) = 0;
    // Number of frames when known in advance, else -1.
    virtual int frameCount() const { return -1; }
    // One line for logs, e.g. "TUM folder /data/teddy (193 frames)".
    virtual std::string description() const = 0;
    // The full ground-truth trajectory (camera-to-world), empty when the source has none.
    virtual const std::vector<TimedPose>& groundTruth() const {
        static const std::vector<TimedPose> none;
        return none;
    }
};

struct SourceOptions {
    std::string calib_path;      // overrides the calibration found with or guessed for the source
    std::string rgb_pattern;     // printf patterns for PPM/PGM sequences, e.g. "frames/%04i.ppm"
    std::string depth_pattern;
    int first_index = 0;         // first index substituted into the patterns
};

// Opens `path` as whatever it is: a TUM RGB-D folder (rgb.txt + depth.txt), a per-frame folder
// (frame-XXXXXX.depth.png), or, with rgb/depth patterns set, a PPM/PGM sequence. Throws IoError
// naming the path and why it is not a known source.
std::unique_ptr<ImageSource> openImageSource(const std::string& path, const SourceOptions& options = {});

}  // namespace voxfuse
