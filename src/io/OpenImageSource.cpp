// openImageSource: decides what kind of input a path is and opens the matching source.

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "FrameReading.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/FrameFolderSource.h"
#include "voxfuse/io/ImageSource.h"
#include "voxfuse/io/OpenNISource.h"
#include "voxfuse/io/PpmPgmSource.h"
#include "voxfuse/io/StrayScannerSource.h"
#include "voxfuse/io/TumSource.h"

namespace voxfuse {

namespace fs = std::filesystem;

namespace {

std::string accepted() {
    return std::string(
               "expected one of: a TUM RGB-D folder (rgb.txt + depth.txt); a per-frame folder "
               "(frame-XXXXXX.depth.png); a Stray Scanner capture (odometry.csv + depth/ + rgb.mp4); a PPM/PGM "
               "sequence (file patterns and a calibration: --rgb, --depth and --calib on the command line); an .oni "
               "recording") +
           (OpenNISource::available() ? "" : " (not in this build: no OpenNI2)");
}

std::string lowerCaseExtension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

bool hasOniExtension(const std::string& path) { return lowerCaseExtension(path) == ".oni"; }

bool holdsFrameFiles(const fs::path& folder) {
    std::error_code ec;
    for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
        int number = 0;
        if (FrameFolderSource::parseDepthFileName(it->path().filename().string(), number)) return true;
    }
    return false;
}

// .bag / .db3 recordings and realsense:[SERIAL] (python/voxfuse/realsense.py reads them).
bool isRealSenseInput(const std::string& path) {
    const std::string ext = lowerCaseExtension(path);
    return path.rfind("realsense:", 0) == 0 || ext == ".bag" || ext == ".db3";
}

// Relative patterns are taken relative to `path` (the sequence folder) when one is given.
std::string resolvePattern(const std::string& path, const std::string& pattern) {
    if (pattern.empty() || path.empty() || fs::path(pattern).is_absolute()) return pattern;
    return (fs::path(path) / pattern).string();
}

}  // namespace

std::unique_ptr<ImageSource> openImageSource(const std::string& path, const SourceOptions& options) {
    if (!options.rgb_pattern.empty() || !options.depth_pattern.empty()) {
        // Named by the folder, else by the pattern given: an empty name reads as ": ..." in a message.
        const std::string named = !path.empty()                  ? path
                                  : !options.rgb_pattern.empty() ? options.rgb_pattern
                                                                 : options.depth_pattern;
        if (options.depth_pattern.empty())
            throw IoError(named,
                          "a PPM/PGM sequence needs a depth file pattern (--depth; SourceOptions::depth_pattern), not "
                          "only an rgb one");
        if (options.calib_path.empty())
            throw IoError(named, "a PPM/PGM sequence needs a calibration file (--calib; SourceOptions::calib_path)");
        return std::make_unique<PpmPgmSource>(resolvePattern(path, options.rgb_pattern),
                                              resolvePattern(path, options.depth_pattern), options.calib_path,
                                              options.first_index);
    }
    if (hasOniExtension(path)) return OpenNISource::openFile(path, options);
    if (isRealSenseInput(path))
        throw IoError(path,
                      "RealSense recordings and cameras are read by the Python package (through pyrealsense2): "
                      "python -m voxfuse " +
                          path + " (pip install . pyrealsense2; see `python -m voxfuse --help`)");

    std::error_code ec;
    if (!fs::exists(path, ec)) throw IoError(path, "no such file or folder; " + accepted());
    if (fs::is_directory(path, ec)) {
        const fs::path folder(path);
        if (frame_reading::fileExists((folder / "rgb.txt").string()) &&
            frame_reading::fileExists((folder / "depth.txt").string()))
            return std::make_unique<TumSource>(path, options.calib_path);
        if (holdsFrameFiles(folder)) return std::make_unique<FrameFolderSource>(path, options.calib_path);
        if (StrayScannerSource::isCapture(path)) return std::make_unique<StrayScannerSource>(path, options);
    }
    throw IoError(path, "not a known image source; " + accepted());
}

}  // namespace voxfuse
