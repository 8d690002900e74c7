// voxfuse_synth: renders the synthetic room (or the long corridor walk of the
// swapping benchmark) as an RGB-D sequence with exact ground truth, in the TUM
// RGB-D layout or as InfiniTAM-style PPM/PGM files; in the TUM layout also with
// exact per-pixel semantic class images.
#include "CameraPath.h"
#include "KinectDepthModel.h"
#include "SyntheticScene.h"
#include "CommandLine.h"
#include "OptionChecks.h"  // addFormerSpelling
#include "voxfuse/io/AtomicFile.h"

#include <CLI/CLI.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace voxfuse::synth;

namespace {

struct Options {
    std::string outDir;
    std::string scene = "room";
    float corridorLength = 20.0f;
    int frames = 100;
    int width = 640;
    int height = 480;
    std::string format = "tum";
    std::string rgbFormat = "jpg";
    int jpegQuality = 90;
    std::uint32_t seed = 1;
    bool noNoise = false;
    bool noLabels = false;
    int colorSamples = 2;
    bool overwrite = false;
};

constexpr double kFirstTimestamp = 1000.0;
constexpr float kTumDepthScale = 5000.0f;  // TUM PNG depth: metres * 5000
constexpr float kColorNoiseSigma = 1.5f;   // sensor noise, 8-bit levels

// Pose line "timestamp tx ty tz qx qy qz qw" plus the pose exactly as a reader
// of that line gets it, so the images match the written ground truth.
struct PoseRecord {
    std::string line;
    Eigen::Isometry3f pose;
};

PoseRecord makePoseRecord(double timestamp, const Eigen::Isometry3f& pose) {
    const Eigen::Vector3f t = pose.translation();
    Eigen::Quaternionf q(pose.linear());
    q.normalize();
    if (q.w() < 0.0f) q.coeffs() *= -1.0f;  // one canonical sign
    char buffer[256];
    std::snprintf(buffer, sizeof(buffer), "%.6f %.7f %.7f %.7f %.7f %.7f %.7f %.7f", timestamp, t.x(), t.y(), t.z(),
                  q.x(), q.y(), q.z(), q.w());
    std::istringstream in(buffer);
    double ts, v[7];
    in >> ts >> v[0] >> v[1] >> v[2] >> v[3] >> v[4] >> v[5] >> v[6];
    const Eigen::Quaterniond qd = Eigen::Quaterniond(v[6], v[3], v[4], v[5]).normalized();
    Eigen::Isometry3d parsed = Eigen::Isometry3d::Identity();
    parsed.linear() = qd.toRotationMatrix();
    parsed.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
    return {buffer, parsed.cast<float>()};
}

std::string timestampName(double timestamp) {
    char buffer[64];
    std::snprintf(buffer, sizeof(buffer), "%.6f", timestamp);
    return buffer;
}

// Every file is written through the library's AtomicFile, which checks the last flush and the close
// (where a full disk shows) and names the file and the reason.
using OutputFile = std::unique_ptr<voxfuse::AtomicFile>;
OutputFile openFile(const fs::path& path) { return std::make_unique<voxfuse::AtomicFile>(path.string()); }

void writeCalib(const fs::path& path, const PinholeCamera& cam, const std::string& disparityLine) {
    const OutputFile file = openFile(path);
    std::ostream& out = file->stream();
    for (int camera = 0; camera < 2; ++camera)  // rgb, then depth: the same sensor
        out << cam.width << " " << cam.height << "\n"
            << cam.fx << " " << cam.fy << "\n"
            << cam.cx << " " << cam.cy << "\n\n";
    out << "1 0 0 0\n0 1 0 0\n0 0 1 0\n\n" << disparityLine << "\n";
    file->commit();
}

// 8-bit interleaved colour with a little Gaussian sensor noise; OpenCV wants BGR.
std::vector<std::uint8_t> toBytes(const std::vector<Eigen::Vector3f>& rgb, std::mt19937* rng, bool bgr) {
    std::normal_distribution<float> noise(0.0f, kColorNoiseSigma);
    std::vector<std::uint8_t> bytes(rgb.size() * 3);
    for (std::size_t i = 0; i < rgb.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            float value = rgb[i][c] * 255.0f + (rng ? noise(*rng) : 0.0f);
            bytes[3 * i + (bgr ? 2 - c : c)] = static_cast<std::uint8_t>(std::clamp(std::round(value), 0.0f, 255.0f));
        }
    return bytes;
}

// Encoded in memory and written as every other file (the codec's own file writer does not check its
// last flush).
void writeImage(const fs::path& path, const cv::Mat& image, const std::vector<int>& params) {
    std::vector<std::uint8_t> bytes;
    if (!cv::imencode(path.extension().string(), image, bytes, params))
        throw std::runtime_error("cannot encode " + path.string());
    const OutputFile file = openFile(path);
    file->stream().write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    file->commit();
}

void writePpm(const fs::path& path, int width, int height, const std::vector<std::uint8_t>& rgb) {
    const OutputFile file = openFile(path);
    file->stream() << "P6\n" << width << " " << height << "\n255\n";
    file->stream().write(reinterpret_cast<const char*>(rgb.data()), static_cast<std::streamsize>(rgb.size()));
    file->commit();
}

// 16-bit binary PGM; the format stores samples big-endian.
void writePgm16(const fs::path& path, int width, int height, const std::vector<std::uint16_t>& values) {
    const OutputFile file = openFile(path);
    file->stream() << "P5\n" << width << " " << height << "\n65535\n";
    std::vector<char> bytes(values.size() * 2);
    for (std::size_t i = 0; i < values.size(); ++i) {
        bytes[2 * i] = static_cast<char>(values[i] >> 8);
        bytes[2 * i + 1] = static_cast<char>(values[i] & 0xFF);
    }
    file->stream().write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    file->commit();
}

// `source` names the rendered sequence in every header ("synthetic_room", "synthetic_corridor").
void writeTumHeader(std::ostream& out, const std::string& source, const std::string& what, const std::string& columns) {
    out << "# " << what << "\n# file: 'voxfuse " << source << " (voxfuse_synth)'\n# " << columns << "\n";
}

// classes.txt: "id name" per semantic class of the scene, as the label images use them.
void writeClasses(const fs::path& path, const std::string& source, const SyntheticScene& scene) {
    const OutputFile file = openFile(path);
    std::ostream& out = file->stream();
    out << "# semantic classes of the label images (labels/*.png, one class id per pixel)\n"
           "# file: 'voxfuse "
        << source
        << " (voxfuse_synth)'\n"
           "# id name   (0 = unlabelled: no surface)\n";
    for (const SemanticClass& c : scene.classes()) out << c.id << " " << c.name << "\n";
    file->commit();
}

// Label PNGs are 8-bit: every class a primitive uses must fit.
void checkClassesFitLabelImages(const SyntheticScene& scene) {
    for (const Primitive& p : scene.primitives())
        if (p.classId > 255)
            throw std::runtime_error("class id " + std::to_string(p.classId) +
                                     " does not fit the 8-bit label images (--no-labels skips them)");
}

// Renders the sequence into `out` (a new, empty folder).
void render(const Options& opt, const fs::path& out) {
    const bool tum = opt.format == "tum";
    const bool labels = tum && !opt.noLabels;
    fs::create_directories(out);
    if (tum) {
        fs::create_directories(out / "rgb");
        fs::create_directories(out / "depth");
    }
    if (labels) fs::create_directories(out / "labels");

    // Render from the scene as read back from scene.txt, so the file is the
    // complete and exact description of what was rendered.
    const bool corridor = opt.scene == "corridor";
    const std::string source = corridor ? "synthetic_corridor" : "synthetic_room";
    (corridor ? SyntheticScene::corridor(opt.corridorLength) : SyntheticScene::defaultRoom())
        .write((out / "scene.txt").string());
    const SyntheticScene scene = SyntheticScene::read((out / "scene.txt").string());
    if (labels) {
        checkClassesFitLabelImages(scene);
        writeClasses(out / "classes.txt", source, scene);
    }

    const PinholeCamera camera = PinholeCamera::kinectV1(opt.width, opt.height);
    const CameraPath room_path;
    const CorridorWalk corridor_walk(opt.corridorLength, opt.frames);
    KinectDepthModel::Params depthParams;
    depthParams.fx = camera.fx;
    std::seed_seq depthSeed{opt.seed, 1u}, colorSeed{opt.seed, 2u};
    std::mt19937 depthRng(depthSeed), colorRng(colorSeed);
    KinectDepthModel depthModel(depthParams, depthRng());

    std::ostringstream disparityLine;
    if (tum)
        disparityLine << "affine " << 1.0f / kTumDepthScale << " 0";
    else
        disparityLine << "kinect " << KinectDepthModel::kKinectK1 << " " << depthParams.baseline;
    writeCalib(out / "calib.txt", camera, disparityLine.str());

    OutputFile groundTruth = openFile(out / "groundtruth.txt");
    writeTumHeader(groundTruth->stream(), source, "ground truth trajectory (camera-to-world, exact)",
                   "timestamp tx ty tz qx qy qz qw");
    OutputFile rgbList, depthList, associations, labelList;
    if (tum) {
        rgbList = openFile(out / "rgb.txt");
        depthList = openFile(out / "depth.txt");
        associations = openFile(out / "associations.txt");
        writeTumHeader(rgbList->stream(), source, "color images", "timestamp filename");
        writeTumHeader(depthList->stream(), source, "depth maps", "timestamp filename");
    }
    if (labels) {
        labelList = openFile(out / "labels.txt");
        writeTumHeader(labelList->stream(), source, "semantic labels (class ids, see classes.txt)",
                       "timestamp filename");
    }

    const std::string rgbExt = opt.rgbFormat == "png" ? ".png" : ".jpg";
    const std::vector<int> rgbParams = opt.rgbFormat == "png"
                                           ? std::vector<int>{cv::IMWRITE_PNG_COMPRESSION, 9}
                                           : std::vector<int>{cv::IMWRITE_JPEG_QUALITY, opt.jpegQuality};
    const std::vector<int> depthPngParams{cv::IMWRITE_PNG_COMPRESSION, 9};

    for (int i = 0; i < opt.frames; ++i) {
        const double timestamp = kFirstTimestamp + i / CameraPath::kFps;
        const PoseRecord pose = makePoseRecord(timestamp, corridor ? corridor_walk.pose(i) : room_path.pose(i));
        groundTruth->stream() << pose.line << "\n";

        const RenderedFrame frame = scene.render(camera, pose.pose, opt.colorSamples);
        const std::vector<float> depth =
            opt.noNoise ? frame.depth : depthModel.apply(frame.depth, frame.cosIncidence, frame.width, frame.height);
        std::vector<std::uint8_t> color = toBytes(frame.rgb, opt.noNoise ? nullptr : &colorRng, /*bgr=*/tum);

        if (tum) {
            const std::string name = timestampName(timestamp);
            const cv::Mat bgr(opt.height, opt.width, CV_8UC3, color.data());
            cv::Mat depthImage(opt.height, opt.width, CV_16UC1);
            for (int v = 0; v < opt.height; ++v)
                for (int u = 0; u < opt.width; ++u) {
                    const float scaled =
                        std::round(depth[static_cast<std::size_t>(v) * opt.width + u] * kTumDepthScale);
                    depthImage.at<std::uint16_t>(v, u) =
                        scaled >= 1.0f && scaled <= 65535.0f ? static_cast<std::uint16_t>(scaled) : 0;
                }
            writeImage(out / "rgb" / (name + rgbExt), bgr, rgbParams);
            writeImage(out / "depth" / (name + ".png"), depthImage, depthPngParams);
            rgbList->stream() << name << " rgb/" << name << rgbExt << "\n";
            depthList->stream() << name << " depth/" << name << ".png\n";
            associations->stream() << name << " rgb/" << name << rgbExt << " " << name << " depth/" << name << ".png\n";
            if (labels) {
                // Exact: the class at each pixel's centre ray, the one that gave the depth.
                cv::Mat labelImage(opt.height, opt.width, CV_8UC1);
                for (int v = 0; v < opt.height; ++v)
                    for (int u = 0; u < opt.width; ++u)
                        labelImage.at<std::uint8_t>(v, u) =
                            static_cast<std::uint8_t>(frame.label[static_cast<std::size_t>(v) * opt.width + u]);
                writeImage(out / "labels" / (name + ".png"), labelImage, depthPngParams);
                labelList->stream() << name << " labels/" << name << ".png\n";
            }
        } else {
            char base[32];
            std::snprintf(base, sizeof(base), "%04i", i);
            std::vector<std::uint16_t> raw(depth.size());
            std::transform(depth.begin(), depth.end(), raw.begin(),
                           [&](float z) { return depthModel.depthToKinectRaw(z); });
            writePpm(out / (std::string(base) + ".ppm"), opt.width, opt.height, color);
            writePgm16(out / (std::string(base) + ".pgm"), opt.width, opt.height, raw);
        }
        std::cout << "\rframe " << (i + 1) << "/" << opt.frames << std::flush;
    }
    for (const OutputFile* file : {&groundTruth, &rgbList, &depthList, &associations, &labelList})
        if (*file) (*file)->commit();
}

// The sequence is rendered into a hidden folder beside the target and renamed into place once every
// file is written: an interrupted or failed run leaves no folder that looks like a complete sequence,
// and an existing one is replaced only with --overwrite.
int run(const Options& opt) {
    fs::path target = fs::path(opt.outDir).lexically_normal();
    if (target.filename().empty()) target = target.parent_path();  // "dir/"
    std::error_code ec;
    if (fs::exists(target, ec)) {
        if (!fs::is_directory(target, ec)) throw std::runtime_error(target.string() + " exists and is not a folder");
        if (!fs::is_empty(target, ec) && !opt.overwrite)
            throw std::runtime_error(target.string() + " exists and is not empty (give --overwrite to replace it)");
    }
    const fs::path staging =
        target.parent_path() / ("." + target.filename().string() + ".partial-" + std::to_string(::getpid()));
    fs::remove_all(staging, ec);
    fs::create_directories(staging);
    try {
        render(opt, staging);
        fs::remove_all(target);
        fs::rename(staging, target);
    } catch (...) {
        fs::remove_all(staging, ec);
        throw;
    }
    std::cout << "\nwrote " << opt.frames << " frames to " << target.string() << "\n";
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{
        "Render the VoxFuse synthetic room, or a walk down a corridor and back, as an RGB-D sequence with exact ground "
        "truth"};
    app.option_defaults()->always_capture_default();  // show defaults in --help
    Options opt;
    app.add_option("--out", opt.outDir,
                   "Output directory (made whole at the end; an existing one that is not empty needs --overwrite)")
        ->required();
    app.add_flag("--overwrite", opt.overwrite, "Replace the output directory if it exists");
    app.add_option("--scene", opt.scene,
                   "room: the orbit of the bundled room; corridor: a walk down a corridor and back in --frames "
                   "frames, a map several times a bounded active memory (swapping benchmark: --frames 1200)")
        ->check(CLI::IsMember({"room", "corridor"}));
    app.add_option("--corridor-length", opt.corridorLength, "Length of the corridor (m)")
        ->check(CLI::Range(2.0f, 1000.0f));
    app.add_option("--frames", opt.frames, "Number of frames (30 fps)")->check(CLI::PositiveNumber);
    app.add_option("--width", opt.width, "Image width (intrinsics scale with it)")->check(CLI::PositiveNumber);
    app.add_option("--height", opt.height, "Image height")->check(CLI::PositiveNumber);
    app.add_option("--format", opt.format, "tum: TUM RGB-D layout; ppm: %04i.ppm + Kinect-raw %04i.pgm")
        ->check(CLI::IsMember({"tum", "ppm"}));
    app.add_option("--rgb-format", opt.rgbFormat, "Colour files in the TUM layout")
        ->check(CLI::IsMember({"jpg", "png"}));
    app.add_option("--jpeg-quality", opt.jpegQuality, "JPEG quality")->check(CLI::Range(1, 100));
    app.add_option("--seed", opt.seed, "Seed of the depth and colour noise");
    CLI::Option* samples =
        app.add_option("--color-samples", opt.colorSamples, "Colour supersampling per axis")->check(CLI::Range(1, 4));
    voxfuse::app::addFormerSpelling(app, "--colour-samples", samples, opt.colorSamples)->check(CLI::Range(1, 4));
    app.add_flag("--no-noise", opt.noNoise, "Exact depth (only the file's own quantisation) and noise-free colour");
    app.add_flag("--no-labels", opt.noLabels,
                 "No semantic label images (TUM layout: labels/*.png, labels.txt, classes.txt)");
    voxfuse::app::addVersionFlag(app, "voxfuse_synth");
    if (const auto status = voxfuse::app::parseCommandLine(app, argc, argv, "voxfuse_synth")) return *status;
    try {
        return run(opt);
    } catch (const std::exception& e) {
        std::cerr << "\nvoxfuse_synth: " << e.what() << "\n";
        return 2;
    }
}
