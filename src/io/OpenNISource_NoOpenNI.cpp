// OpenNISource in a build without OpenNI2 (VOXFUSE_OPENNI2=OFF): every open says how to get it.

#include "voxfuse/io/OpenNISource.h"

#include "voxfuse/core/Error.h"

namespace voxfuse {

namespace {
const char* const kNotBuilt =
    "OpenNI2 input is not available in this build: install OpenNI2 (Debian: apt-get install libopenni2-dev) and "
    "configure with -DVOXFUSE_OPENNI2=ON";
}  // namespace

struct OpenNISource::Impl {};

bool OpenNISource::available() { return false; }

OpenNISource::OpenNISource(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
OpenNISource::~OpenNISource() = default;

std::unique_ptr<OpenNISource> OpenNISource::openFile(const std::string& path, const SourceOptions&) {
    throw IoError(path, kNotBuilt);
}

std::unique_ptr<OpenNISource> OpenNISource::openDevice(const std::string& uri, const SourceOptions&) {
    throw IoError(uri.empty() ? "OpenNI2 camera" : uri, kNotBuilt);
}

std::vector<std::string> OpenNISource::deviceUris() { return {}; }

// Unreachable: no OpenNISource object can exist in this build.
const RGBDCalib& OpenNISource::calib() const {
    static const RGBDCalib none;
    return none;
}
bool OpenNISource::next(RGBDFrame&) { return false; }
int OpenNISource::frameCount() const { return 0; }
std::string OpenNISource::description() const { return "OpenNI2 (not in this build)"; }
bool OpenNISource::isLive() const { return false; }

}  // namespace voxfuse
