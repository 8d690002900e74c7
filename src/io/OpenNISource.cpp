// OpenNI2 input (built with VOXFUSE_OPENNI2): live cameras and .oni playback.

#include "voxfuse/io/OpenNISource.h"

#include <OpenNI.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <thread>

#include "voxfuse/core/Error.h"
#include "voxfuse/io/CalibIO.h"

namespace voxfuse {

namespace {

// How long a next() waits for any frame: a camera delivers at 30 Hz and playback in milliseconds,
// but a camera's first frames can take a second or two after the streams start.
constexpr int kFrameTimeoutMs = 5000;
constexpr double kKinectFocalAt640 = 525.0;  // Kinect v1 colour camera, the usual default

std::string extendedError() {
    std::string text = openni::OpenNI::getExtendedError();
    while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' ')) text.pop_back();
    while (!text.empty() && (text.front() == '\t' || text.front() == ' ')) text.erase(text.begin());
    return text.empty() ? "no details from OpenNI2" : text;
}

std::string sizeText(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

// Initialises OpenNI2 once, at the first use, and keeps it for the rest of the process. Shutting
// it down with the last source and initialising it again with the next one would reload every
// driver each time (a quarter of a second) and leaks what the drivers allocate, cycle after cycle.
class OpenNIRuntime {
public:
    OpenNIRuntime() {
        static const std::string failure = [] {
            if (openni::OpenNI::initialize() == openni::STATUS_OK) return std::string();
            return "cannot initialise OpenNI2 (" + extendedError() +
                   "); are its drivers installed? Debian's libopenni2-0 puts them in /usr/lib/<arch>/OpenNI2/Drivers";
        }();
        if (!failure.empty()) throw IoError("OpenNI2", failure);
    }
};

// Intrinsics of a w x h image with the given fields of view (radians), or the Kinect v1 default
// focal length when the stream does not report them (OpenNI 1.x recordings of colour, for one).
Intrinsics intrinsicsFromFieldOfView(int w, int h, float hfov, float vfov, bool& from_fov) {
    const auto plausible = [](float fov) { return std::isfinite(fov) && fov > 0.2f && fov < 2.8f; };
    from_fov = plausible(hfov) && plausible(vfov);
    const double fx = from_fov ? 0.5 * w / std::tan(0.5 * hfov) : kKinectFocalAt640 * w / 640.0;
    const double fy = from_fov ? 0.5 * h / std::tan(0.5 * vfov) : fx;
    return Intrinsics{w, h, float(fx), float(fy), 0.5f * float(w - 1), 0.5f * float(h - 1)};
}

Image<Vec4u8> copyOf(const Image<Vec4u8>& image) {
    Image<Vec4u8> copy(image.size());
    if (!image.empty()) std::memcpy(static_cast<void*>(copy.host()), image.host(), image.pixelCount() * sizeof(Vec4u8));
    return copy;
}

// Picks 640x480 at 30 Hz in the first of `formats` the sensor offers; keeps the default mode otherwise.
void preferVgaMode(openni::VideoStream& stream, std::initializer_list<openni::PixelFormat> formats) {
    const openni::Array<openni::VideoMode>& modes = stream.getSensorInfo().getSupportedVideoModes();
    for (openni::PixelFormat format : formats)
        for (int i = 0; i < modes.getSize(); ++i) {
            const openni::VideoMode& m = modes[i];
            if (m.getResolutionX() == 640 && m.getResolutionY() == 480 && m.getFps() == 30 &&
                m.getPixelFormat() == format && stream.setVideoMode(m) == openni::STATUS_OK)
                return;
        }
}

// Mirroring off; true when the stream stays mirrored (recordings cannot change it), so that the
// frames must be flipped back here.
bool mustUnmirror(openni::VideoStream& stream) {
    if (!stream.getMirroringEnabled()) return false;
    return stream.setMirroringEnabled(false) != openni::STATUS_OK || stream.getMirroringEnabled();
}

}  // namespace

struct OpenNISource::Impl {
    struct DepthRecord {
        std::uint64_t time_us = 0;
        Image<std::uint16_t> image;
    };
    struct ColorRecord {
        std::uint64_t time_us = 0;
        Image<Vec4u8> image;
    };

    Impl(std::string source_name, bool is_live) : name(std::move(source_name)), live(is_live) {}
    // Then the members go in reverse order: the streams before the device.
    ~Impl() {
        color.stop();
        depth.stop();
        // A camera driver's threads may still be delivering a frame; some drivers (OpenNI2's own
        // sample "Dummy" device among them) do not wait for them before a stream is destroyed.
        if (live) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }

    void openStreams();
    void registerDepthToColor();
    void calibrate(const std::string& calib_path);
    bool next(RGBDFrame& frame);
    std::string description() const;

    // One frame of either stream, in arrival order; false at the end of a recording.
    bool readRecord(std::optional<DepthRecord>& depth_record, std::optional<ColorRecord>& color_record);
    Image<std::uint16_t> convertDepth(const openni::VideoFrameRef& f) const;
    Image<Vec4u8> convertColor(const openni::VideoFrameRef& f) const;
    void checkFrame(const openni::VideoFrameRef& f, int bytes_per_pixel, const char* what,
                    const Intrinsics& camera) const;
    [[noreturn]] void failOpening(const std::string& reason) const { throw IoError(name, reason); }
    [[noreturn]] void failFrame(const std::string& reason) const { throw IoError(name, reason, delivered); }

    OpenNIRuntime runtime;
    openni::Device device;
    openni::VideoStream depth;
    openni::VideoStream color;

    std::string name;  // file path or device URI, for messages
    bool live;
    bool has_color = false;
    bool unmirror_depth = false, unmirror_color = false;
    bool registered = false;
    std::string registration_note;
    RGBDCalib calib;
    std::string calib_origin;
    int depth_total = -1, color_total = -1;  // frames in a recording
    int depth_read = 0, color_read = 0;
    int delivered = 0;     // frames handed out (the next frame's index)
    bool stalled = false;  // a recording that stopped delivering frames

    std::optional<DepthRecord> pending;    // the depth frame next() delivers
    std::optional<DepthRecord> following;  // a depth frame read while looking ahead for colour
    std::optional<ColorRecord> latest;     // the newest colour frame read
};

void OpenNISource::Impl::openStreams() {
    if (!device.hasSensor(openni::SENSOR_DEPTH)) failOpening("has no depth stream");
    if (depth.create(device, openni::SENSOR_DEPTH) != openni::STATUS_OK)
        failOpening("cannot create the depth stream: " + extendedError());
    has_color =
        device.hasSensor(openni::SENSOR_COLOR) && color.create(device, openni::SENSOR_COLOR) == openni::STATUS_OK;
    if (live) {
        preferVgaMode(depth, {openni::PIXEL_FORMAT_DEPTH_1_MM, openni::PIXEL_FORMAT_DEPTH_100_UM});
        if (has_color) preferVgaMode(color, {openni::PIXEL_FORMAT_RGB888});
    }
    const openni::PixelFormat depth_format = depth.getVideoMode().getPixelFormat();
    if (depth_format != openni::PIXEL_FORMAT_DEPTH_1_MM && depth_format != openni::PIXEL_FORMAT_DEPTH_100_UM)
        failOpening("the depth stream's pixel format (" + std::to_string(int(depth_format)) +
                    ") is not depth in millimetres or 100 micrometres");
    if (has_color) {
        const openni::PixelFormat color_format = color.getVideoMode().getPixelFormat();
        if (color_format != openni::PIXEL_FORMAT_RGB888 && color_format != openni::PIXEL_FORMAT_GRAY8)
            failOpening("the colour stream's pixel format (" + std::to_string(int(color_format)) +
                        ") is not RGB888 or GRAY8");
    }
    unmirror_depth = mustUnmirror(depth);
    unmirror_color = has_color && mustUnmirror(color);
    registerDepthToColor();
    if (live && has_color) device.setDepthColorSyncEnabled(true);  // best effort: pairs arrive together

    if (openni::PlaybackControl* playback = device.getPlaybackControl()) {
        // Manual stepping: the player delivers one record each time waitForAnyStream finds none
        // pending, so no frame is ever overwritten before it is read.
        playback->setSpeed(-1.0f);
        playback->setRepeatEnabled(false);
        depth_total = playback->getNumberOfFrames(depth);
        color_total = has_color ? playback->getNumberOfFrames(color) : 0;
        if (depth_total <= 0) failOpening("the recording holds no depth frames");
    }
    if (depth.start() != openni::STATUS_OK) failOpening("cannot start the depth stream: " + extendedError());
    if (has_color && color.start() != openni::STATUS_OK)
        failOpening("cannot start the colour stream: " + extendedError());
}

void OpenNISource::Impl::registerDepthToColor() {
    if (!has_color) {
        registration_note = "no colour stream";
        return;
    }
    if (live) {
        if (device.isImageRegistrationModeSupported(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR))
            device.setImageRegistrationMode(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR);
        registered = device.getImageRegistrationMode() == openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR;
        registration_note = registered ? "depth registered to colour" : "depth NOT registered to colour (unsupported)";
        return;
    }
    // OpenNI2's player does not expose whether the recorder registered depth (OpenNI 1.x stores it
    // as the depth node's "AlternativeViewPoint"); reconstruction recordings almost always are.
    registered = true;
    registration_note = device.getImageRegistrationMode() == openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR
                            ? "depth registered to colour"
                            : "depth assumed registered to colour (the player does not say; give a calibration "
                              "file otherwise)";
}

void OpenNISource::Impl::calibrate(const std::string& calib_path) {
    const openni::VideoMode depth_mode = depth.getVideoMode();
    const int dw = depth_mode.getResolutionX(), dh = depth_mode.getResolutionY();
    if (!calib_path.empty()) {
        calib = readCalib(calib_path);
        if (calib.depth.size() != Vec2i{dw, dh})
            throw IoError(calib_path, "the depth camera is " + sizeText(calib.depth.width, calib.depth.height) +
                                          " but " + name + " streams depth at " + sizeText(dw, dh));
        if (has_color) {
            const openni::VideoMode m = color.getVideoMode();
            if (calib.rgb.size() != Vec2i{m.getResolutionX(), m.getResolutionY()})
                throw IoError(calib_path, "the RGB camera is " + sizeText(calib.rgb.width, calib.rgb.height) + " but " +
                                              name + " streams colour at " +
                                              sizeText(m.getResolutionX(), m.getResolutionY()));
        }
        calib_origin = calib_path;
        return;
    }
    bool depth_from_fov = false, color_from_fov = false;
    calib.depth = intrinsicsFromFieldOfView(dw, dh, depth.getHorizontalFieldOfView(), depth.getVerticalFieldOfView(),
                                            depth_from_fov);
    calib.rgb = calib.depth;
    if (has_color) {
        const openni::VideoMode m = color.getVideoMode();
        calib.rgb = intrinsicsFromFieldOfView(m.getResolutionX(), m.getResolutionY(), color.getHorizontalFieldOfView(),
                                              color.getVerticalFieldOfView(), color_from_fov);
        if (registered) {  // depth now sees through the colour camera
            const float sx = float(dw) / float(calib.rgb.width), sy = float(dh) / float(calib.rgb.height);
            calib.depth = Intrinsics{dw,
                                     dh,
                                     calib.rgb.fx * sx,
                                     calib.rgb.fy * sy,
                                     (calib.rgb.cx + 0.5f) * sx - 0.5f,
                                     (calib.rgb.cy + 0.5f) * sy - 0.5f};
            depth_from_fov = color_from_fov;
        }
    }
    calib.T_depth_rgb = Mat4f::identity();  // registered; unregistered: the baseline is unknown here
    calib.disparity = DisparityCalib::affine(
        depth_mode.getPixelFormat() == openni::PIXEL_FORMAT_DEPTH_100_UM ? 0.0001f : 0.001f, 0.f);
    calib_origin =
        depth_from_fov ? "the streams' fields of view" : "Kinect v1 defaults (the stream reports no field of view)";
}

void OpenNISource::Impl::checkFrame(const openni::VideoFrameRef& f, int bytes_per_pixel, const char* what,
                                    const Intrinsics& camera) const {
    const int w = f.getWidth(), h = f.getHeight(), stride = f.getStrideInBytes();
    if (w <= 0 || h <= 0 || stride < w * bytes_per_pixel || f.getDataSize() < stride * h || f.getData() == nullptr)
        failFrame(std::string("malformed ") + what + " frame (" + sizeText(w, h) + ", stride " +
                  std::to_string(stride) + ", " + std::to_string(f.getDataSize()) + " bytes)");
    if (Vec2i{w, h} != camera.size())
        failFrame(std::string(what) + " frame is " + sizeText(w, h) + " but the calibration's " + what + " camera is " +
                  sizeText(camera.width, camera.height));
}

Image<std::uint16_t> OpenNISource::Impl::convertDepth(const openni::VideoFrameRef& f) const {
    checkFrame(f, 2, "depth", calib.depth);
    const openni::PixelFormat format = f.getVideoMode().getPixelFormat();
    if (format != depth.getVideoMode().getPixelFormat())
        failFrame("the depth pixel format changed during the stream (" + std::to_string(int(format)) + ")");
    const int w = f.getWidth(), h = f.getHeight();
    Image<std::uint16_t> image({w, h});
    for (int y = 0; y < h; ++y) {
        const auto* row = reinterpret_cast<const std::uint16_t*>(static_cast<const std::uint8_t*>(f.getData()) +
                                                                 std::size_t(y) * std::size_t(f.getStrideInBytes()));
        std::uint16_t* out = &image.at(0, y);
        if (unmirror_depth)
            for (int x = 0; x < w; ++x) out[x] = row[w - 1 - x];
        else
            std::memcpy(out, row, std::size_t(w) * sizeof(std::uint16_t));
    }
    return image;
}

Image<Vec4u8> OpenNISource::Impl::convertColor(const openni::VideoFrameRef& f) const {
    const openni::PixelFormat format = f.getVideoMode().getPixelFormat();
    const bool grey = format == openni::PIXEL_FORMAT_GRAY8;
    if (!grey && format != openni::PIXEL_FORMAT_RGB888)
        failFrame("unsupported colour pixel format " + std::to_string(int(format)) + " (expected RGB888 or GRAY8)");
    checkFrame(f, grey ? 1 : 3, "rgb", calib.rgb);
    const int w = f.getWidth(), h = f.getHeight();
    Image<Vec4u8> image({w, h});
    for (int y = 0; y < h; ++y) {
        const std::uint8_t* row =
            static_cast<const std::uint8_t*>(f.getData()) + std::size_t(y) * std::size_t(f.getStrideInBytes());
        for (int x = 0; x < w; ++x) {
            const std::uint8_t* p = row + (unmirror_color ? w - 1 - x : x) * (grey ? 1 : 3);
            image.at(x, y) = grey ? Vec4u8{p[0], p[0], p[0], 255} : Vec4u8{p[0], p[1], p[2], 255};
        }
    }
    return image;
}

bool OpenNISource::Impl::readRecord(std::optional<DepthRecord>& depth_record,
                                    std::optional<ColorRecord>& color_record) {
    if (stalled) return false;
    if (!live && depth_read >= depth_total && color_read >= color_total) return false;
    openni::VideoStream* streams[2] = {&depth, &color};
    int ready = -1;
    if (openni::OpenNI::waitForAnyStream(streams, has_color ? 2 : 1, &ready, kFrameTimeoutMs) != openni::STATUS_OK) {
        if (live)
            failFrame("no frame from the camera for " + std::to_string(kFrameTimeoutMs / 1000) +
                      " s (unplugged, or busy?)");
        stalled = true;
        failFrame("playback stalled after " + std::to_string(depth_read) + " of " + std::to_string(depth_total) +
                  " depth frames (no frame for " + std::to_string(kFrameTimeoutMs / 1000) +
                  " s; a damaged recording?)");
    }
    openni::VideoFrameRef f;
    if (streams[ready]->readFrame(&f) != openni::STATUS_OK || !f.isValid())
        failFrame("OpenNI2 could not read a frame: " + extendedError());
    if (ready == 0) {
        ++depth_read;
        depth_record = DepthRecord{f.getTimestamp(), convertDepth(f)};
    } else {
        ++color_read;
        color_record = ColorRecord{f.getTimestamp(), convertColor(f)};
    }
    return true;
}

bool OpenNISource::Impl::next(RGBDFrame& frame) {
    if (!pending) pending.swap(following);
    while (!pending) {
        std::optional<ColorRecord> color_record;
        if (!readRecord(pending, color_record)) return false;
        if (color_record) latest = std::move(color_record);
    }
    // The colour frame nearest in time may arrive just after the depth frame: look one record ahead.
    // (A throw here keeps `pending`, so the next call delivers it.)
    const std::uint64_t t = pending->time_us;
    const auto distance = [t](std::uint64_t u) { return u > t ? u - t : t - u; };
    const ColorRecord* best = latest ? &*latest : nullptr;
    std::optional<ColorRecord> after;
    if (has_color && !following && (!latest || latest->time_us < t) && readRecord(following, after) && after) {
        if (!best || distance(after->time_us) < distance(best->time_us)) best = &*after;
    }
    frame.depth_raw = std::move(pending->image);
    frame.rgb = best ? copyOf(best->image) : Image<Vec4u8>();
    frame.index = delivered++;
    frame.timestamp_s = double(t) * 1e-6;
    frame.depth_path = name;
    frame.has_ground_truth = false;
    frame.T_world_camera_gt = Mat4f::identity();
    pending.reset();
    if (after) latest = std::move(after);
    return true;
}

std::string OpenNISource::Impl::description() const {
    const openni::VideoMode m = depth.getVideoMode();
    std::string text = live ? "OpenNI2 camera " + name : "OpenNI2 recording " + name;
    text += " (depth " + sizeText(m.getResolutionX(), m.getResolutionY());
    if (!live)
        text += ", " + std::to_string(depth_total) + " depth and " + std::to_string(color_total) + " colour frames";
    text += ", " + registration_note;
    if (unmirror_depth || unmirror_color) text += ", mirrored frames flipped back";
    return text + ", calibration from " + calib_origin + ")";
}

// ---------------------------------------------------------------------------------------------

bool OpenNISource::available() { return true; }

OpenNISource::OpenNISource(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
OpenNISource::~OpenNISource() = default;

std::unique_ptr<OpenNISource> OpenNISource::openFile(const std::string& path, const SourceOptions& options) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw IoError(path, "no such file");
    auto impl = std::make_unique<Impl>(path, false);
    if (impl->device.open(path.c_str()) != openni::STATUS_OK)
        throw IoError(path, "OpenNI2 cannot play this file (" + extendedError() +
                                "): it is not an .oni recording, or it is damaged or truncated (OpenNI2 reads the "
                                "frame index at the end of the file)");
    if (!impl->device.isFile()) throw IoError(path, "OpenNI2 opened this as a device, not as a recording");
    impl->openStreams();
    impl->calibrate(options.calib_path);
    return std::unique_ptr<OpenNISource>(new OpenNISource(std::move(impl)));
}

std::unique_ptr<OpenNISource> OpenNISource::openDevice(const std::string& uri, const SourceOptions& options) {
    auto impl = std::make_unique<Impl>(uri.empty() ? std::string("OpenNI2 camera") : uri, true);
    openni::Array<openni::DeviceInfo> devices;
    openni::OpenNI::enumerateDevices(&devices);
    // With a URI, try it even when nothing is listed: some drivers only answer when asked by name.
    if (uri.empty() && devices.getSize() == 0)
        throw IoError(impl->name,
                      "no OpenNI2 camera found: none is connected, its driver is missing (Debian's libopenni2-0 drives "
                      "PrimeSense/Asus Xtion cameras; a Kinect v1 needs libfreenect's OpenNI2 driver in the OpenNI2 "
                      "Drivers folder), or this user may not access its USB device (udev rules)");
    if (impl->device.open(uri.empty() ? openni::ANY_DEVICE : uri.c_str()) != openni::STATUS_OK) {
        std::string connected;
        for (int i = 0; i < devices.getSize(); ++i) connected += std::string(i ? ", " : "") + devices[i].getUri();
        throw IoError(impl->name, "cannot open the camera (" + extendedError() +
                                      "); connected cameras: " + (connected.empty() ? std::string("none") : connected));
    }
    if (impl->device.isFile()) throw IoError(uri, "is a recording, not a camera: open it with OpenNISource::openFile");
    impl->name = impl->device.getDeviceInfo().getUri();
    impl->openStreams();
    impl->calibrate(options.calib_path);
    return std::unique_ptr<OpenNISource>(new OpenNISource(std::move(impl)));
}

std::vector<std::string> OpenNISource::deviceUris() {
    OpenNIRuntime runtime;
    openni::Array<openni::DeviceInfo> devices;
    openni::OpenNI::enumerateDevices(&devices);
    std::vector<std::string> uris;
    for (int i = 0; i < devices.getSize(); ++i) uris.emplace_back(devices[i].getUri());
    return uris;
}

const RGBDCalib& OpenNISource::calib() const { return impl_->calib; }
bool OpenNISource::next(RGBDFrame& frame) { return impl_->next(frame); }
int OpenNISource::frameCount() const { return impl_->live ? -1 : impl_->depth_total; }
std::string OpenNISource::description() const { return impl_->description(); }
bool OpenNISource::isLive() const { return impl_->live; }

}  // namespace voxfuse
