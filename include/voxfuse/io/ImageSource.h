#pragma once
// The one interface every input (files, TUM folders, per-frame folders, iPhone captures, OpenNI)
// implements.

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
    // True for a camera that produces frames whether or not they are read (frames not read in time
    // are lost); false for recordings, which wait for the reader. ThreadedImageSource drops frames
    // of live sources when the engine lags and never drops frames of recordings.
    virtual bool isLive() const { return false; }
};

struct SourceOptions {
    std::string calib_path;   // overrides the calibration found with or guessed for the source
    std::string rgb_pattern;  // printf patterns for PPM/PGM sequences, e.g. "frames/%04i.ppm"
    std::string depth_pattern;
    int first_index = 0;  // first index substituted into the patterns
    // iPhone LiDAR captures (Stray Scanner): depth samples whose confidence (0 low, 1 medium, 2 high)
    // is below this are dropped (set to 0); 0 keeps every sample. Medium and high are kept by default
    // because low-confidence LiDAR depth is mostly wrong at edges and on dark or shiny surfaces.
    int min_depth_confidence = 1;
    // iPhone captures: colour wider than this is downscaled as it is read (aspect ratio kept, the
    // intrinsics scaled to match); 0 keeps the full resolution. A 1920x1440 video frame costs 11 MB
    // as RGBA, and the engine samples colour at depth resolution (256x192) anyway. Other sources
    // deliver colour as recorded.
    int max_color_width = 640;
};

// Opens `path` as whatever it is: a TUM RGB-D folder (rgb.txt + depth.txt), a per-frame folder
// (frame-XXXXXX.depth.png), a Stray Scanner capture (odometry.csv + depth/ + rgb.mp4), an OpenNI
// recording (*.oni, needs a build with OpenNI2), or, with rgb/depth patterns set, a PPM/PGM
// sequence. Throws IoError naming the path and why it is not a known source.
std::unique_ptr<ImageSource> openImageSource(const std::string& path, const SourceOptions& options = {});

}  // namespace voxfuse
