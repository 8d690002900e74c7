// calib.txt reading and writing, and the well-known calibrations that ship in calib/.

#include "voxfuse/io/CalibIO.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <iostream>
#include <utility>
#include <vector>

#include "TextParsing.h"
#include "voxfuse/io/AtomicFile.h"
#include "voxfuse/core/Error.h"

namespace voxfuse {

namespace {

constexpr int kMaxImageSide = 1 << 14;  // pixels: larger is no depth camera, and pixel counts must fit an int

// Hands out the content lines of a file (blank and '#' lines skipped) with their 1-based numbers,
// so that every error can say where it happened.
class CalibLineReader {
public:
    explicit CalibLineReader(const std::string& path) : lines_(path, "calibration file") {}

    // The next content line split into tokens (views into line(): valid until the next call); at the
    // end of the file, a ParseError on the last line saying what was expected.
    std::vector<std::string_view> next(const std::string& expected) {
        if (findTrailingContent()) return text::splitWhitespace(line_);
        throw ParseError(path(), std::max(lines_.lineNumber(), 1), "unexpected end of file: expected " + expected);
    }
    // The first content line after the last block, if any (line_number() then names it).
    bool findTrailingContent() {
        while (lines_.next(line_))
            if (!text::isBlankOrComment(line_)) return true;
        return false;
    }
    int lineNumber() const { return lines_.lineNumber(); }
    const std::string& line() const { return line_; }
    const std::string& path() const { return lines_.path(); }
    [[noreturn]] void fail(const std::string& reason) const { failAt(lines_.lineNumber(), reason); }
    [[noreturn]] void failAt(int line_number, const std::string& reason) const {
        throw ParseError(path(), line_number, reason);
    }

private:
    text::LineReader lines_;
    std::string line_;
};

// One line of exactly `count` numbers, each finite as a float (the type they are stored in).
std::vector<double> readNumbers(CalibLineReader& reader, std::size_t count, const std::string& what) {
    const auto tokens = reader.next(what);
    if (tokens.size() != count)
        reader.fail("expected " + std::to_string(count) + " numbers (" + what + "), got " +
                    std::to_string(tokens.size()) + ": " + text::excerpt(reader.line()));
    std::vector<double> values;
    std::string bad;
    if (!text::parseDoubles(tokens, values, bad))
        reader.fail("not a number: " + text::excerpt(bad) + " (" + what + ")");
    for (std::size_t i = 0; i < values.size(); ++i)
        if (!text::finiteAsFloat(values[i]))
            reader.fail("non-finite value " + text::excerpt(tokens[i]) + " in " + what +
                        " (numbers are stored as floats)");
    return values;
}

Intrinsics readCamera(CalibLineReader& reader, const std::string& camera) {
    Intrinsics k;
    {
        const std::string what = camera + " image size: width height";
        const auto tokens = reader.next(what);
        if (tokens.size() != 2)
            reader.fail("expected 2 integers (" + what + "), got " + std::to_string(tokens.size()) + ": " +
                        text::excerpt(reader.line()));
        for (int i = 0; i < 2; ++i) {
            int& v = i == 0 ? k.width : k.height;
            if (!text::parseInt(tokens[std::size_t(i)], v))
                reader.fail("not an integer: " + text::excerpt(tokens[std::size_t(i)]) + " (" + what + ")");
        }
        if (k.width <= 0 || k.height <= 0)
            reader.fail(camera + " image size must be positive, got " + std::to_string(k.width) + "x" +
                        std::to_string(k.height));
        if (k.width > kMaxImageSide || k.height > kMaxImageSide)
            reader.fail(camera + " image size " + std::to_string(k.width) + "x" + std::to_string(k.height) +
                        " is larger than " + std::to_string(kMaxImageSide) + " pixels on a side");
    }
    {
        const auto f = readNumbers(reader, 2, camera + " focal lengths: fx fy");
        k.fx = float(f[0]);
        k.fy = float(f[1]);
        if (!(k.fx > 0.f) || !(k.fy > 0.f))
            reader.fail(camera + " focal lengths must be positive, got " + text::excerpt(reader.line()));
        const std::string problem = focalLengthProblem(k);
        if (!problem.empty()) reader.fail(camera + " " + problem);
    }
    {
        const auto c = readNumbers(reader, 2, camera + " principal point: cx cy");
        k.cx = float(c[0]);
        k.cy = float(c[1]);
        // Pixel centres are at integers: the image spans -0.5 .. size - 0.5.
        if (!(k.cx >= -0.5f && k.cx <= float(k.width) - 0.5f && k.cy >= -0.5f && k.cy <= float(k.height) - 0.5f))
            reader.fail(camera + " principal point (" + text::formatFloat(k.cx) + ", " + text::formatFloat(k.cy) +
                        ") lies outside its " + std::to_string(k.width) + "x" + std::to_string(k.height) +
                        " image (are fx fy and cx cy swapped?)");
    }
    return k;
}

Mat4f readExtrinsics(CalibLineReader& reader) {
    Mat4f T = Mat4f::identity();
    double R[9];
    int first_line = 0;
    for (int r = 0; r < 3; ++r) {
        const auto row = readNumbers(reader, 4, "row " + std::to_string(r + 1) + " of the 3x4 rgb-to-depth extrinsics");
        if (r == 0) first_line = reader.lineNumber();
        for (int c = 0; c < 4; ++c) T(r, c) = float(row[std::size_t(c)]);
        for (int c = 0; c < 3; ++c) R[3 * r + c] = double(T(r, c));
    }
    // A rotation that is far from orthonormal means rows were mistyped or a different matrix was
    // pasted; catching it here beats a silently skewed colour mapping.
    const std::string problem = text::rotationProblem(R);
    if (!problem.empty()) reader.failAt(first_line, "the rotation part of the rgb-to-depth extrinsics is " + problem);
    const std::string position = text::positionProblem(T(0, 3), T(1, 3), T(2, 3));
    if (!position.empty()) reader.failAt(first_line, "the rgb-to-depth extrinsics' " + position);
    return T;
}

DisparityCalib readDisparity(CalibLineReader& reader, float fx_depth) {
    const std::string what = "disparity calibration: 'kinect k1 k2', 'affine a b' or 'k1 k2'";
    auto tokens = reader.next(what);
    std::string keyword = "kinect";  // the bare two-number form is InfiniTAM's Kinect disparity
    double first = 0.0;
    const bool explicit_keyword = !tokens.empty() && !text::parseDouble(tokens[0], first);
    if (explicit_keyword) {
        keyword = std::string(tokens[0]);
        if (keyword != "kinect" && keyword != "affine")
            reader.fail("unknown disparity calibration type " + text::excerpt(keyword) +
                        " (expected 'kinect' or 'affine')");
        tokens.erase(tokens.begin());
    }
    if (tokens.size() != 2)
        reader.fail((explicit_keyword ? "expected 2 numbers after the disparity type '" + keyword + "'"
                                      : "expected 2 numbers (" + what + ")") +
                    ", got " + std::to_string(tokens.size()) + ": " + text::excerpt(reader.line()));
    std::vector<double> v;
    std::string bad;
    if (!text::parseDoubles(tokens, v, bad)) reader.fail("not a number: " + text::excerpt(bad) + " (" + what + ")");
    if (!text::finiteAsFloat(v[0]) || !text::finiteAsFloat(v[1]))
        reader.fail("non-finite value in the disparity calibration (numbers are stored as floats): " +
                    text::excerpt(reader.line()));
    if (keyword == "affine" && !(float(v[0]) > 0.f))
        reader.fail("affine depth scale must be positive, got " + std::string(tokens[0]));
    if (keyword != "affine" && !(float(v[1]) > 0.f))
        reader.fail("kinect disparity k2 must be positive, got " + std::string(tokens[1]));
    const DisparityCalib d = keyword == "affine" ? DisparityCalib::affine(float(v[0]), float(v[1]))
                                                 : DisparityCalib::kinect(float(v[0]), float(v[1]));
    const std::string problem = depthConversionProblem(d, fx_depth);
    if (!problem.empty()) reader.fail(problem);
    return d;
}

// The optional lines after the disparity calibration: "distortion_rgb k1 k2 p1 p2 k3" and
// "distortion_depth k1 k2 p1 p2 k3", each at most once, in either order. Anything else there is an
// error, so a typo cannot silently drop a camera's distortion.
void readDistortionLines(CalibLineReader& reader, RGBDCalib& calib) {
    bool seen_rgb = false, seen_depth = false;
    while (reader.findTrailingContent()) {
        auto tokens = text::splitWhitespace(reader.line());
        const std::string keyword(tokens.front());
        const bool is_rgb = keyword == "distortion_rgb";
        if (!is_rgb && keyword != "distortion_depth")
            reader.fail("unexpected content after the disparity calibration: " + text::excerpt(reader.line()) +
                        " (only 'distortion_rgb k1 k2 p1 p2 k3' and 'distortion_depth k1 k2 p1 p2 k3' may follow)");
        bool& seen = is_rgb ? seen_rgb : seen_depth;
        if (seen) reader.fail("'" + keyword + "' is given twice");
        seen = true;
        tokens.erase(tokens.begin());
        if (tokens.size() != 5)
            reader.fail("expected 5 numbers after '" + keyword + "' (k1 k2 p1 p2 k3), got " +
                        std::to_string(tokens.size()) + ": " + text::excerpt(reader.line()));
        std::vector<double> v;
        std::string bad;
        if (!text::parseDoubles(tokens, v, bad))
            reader.fail("not a number: " + text::excerpt(bad) + " (" + keyword + ")");
        for (double x : v)
            if (!text::finiteAsFloat(x))
                reader.fail("non-finite value in " + keyword + " (numbers are stored as floats)");
        LensDistortion& d = is_rgb ? calib.rgb_distortion : calib.depth_distortion;
        d = LensDistortion{float(v[0]), float(v[1]), float(v[2]), float(v[3]), float(v[4])};
        const std::string problem = distortionProblem(d, is_rgb ? calib.rgb : calib.depth);
        if (!problem.empty()) reader.fail(keyword + ": " + problem);
    }
}

std::string numbers(std::initializer_list<float> values) {
    std::string line;
    for (float v : values) line += (line.empty() ? "" : " ") + text::formatFloat(v);
    return line + "\n";
}

std::string cameraBlock(const Intrinsics& k) {
    return std::to_string(k.width) + " " + std::to_string(k.height) + "\n" + numbers({k.fx, k.fy}) +
           numbers({k.cx, k.cy});
}

}  // namespace

RGBDCalib readCalib(const std::string& path) {
    CalibLineReader reader(path);
    RGBDCalib calib;
    calib.rgb = readCamera(reader, "RGB camera");
    calib.depth = readCamera(reader, "depth camera");
    calib.T_depth_rgb = readExtrinsics(reader);
    calib.disparity = readDisparity(reader, calib.depth.fx);
    readDistortionLines(reader, calib);
    for (const std::string& warning : calibrationWarnings(calib))
        std::cerr << "voxfuse: warning: " << path << ": " << warning << "\n";
    return calib;
}

void writeCalib(const std::string& path, const RGBDCalib& calib) {
    AtomicFile file(path);
    std::ostream& out = file.stream();
    const Mat4f& T = calib.T_depth_rgb;
    out << cameraBlock(calib.rgb) << '\n' << cameraBlock(calib.depth) << '\n';
    for (int r = 0; r < 3; ++r) out << numbers({T(r, 0), T(r, 1), T(r, 2), T(r, 3)});
    out << '\n'
        << (calib.disparity.type == DisparityCalib::Type::Kinect ? "kinect " : "affine ")
        << numbers({calib.disparity.a, calib.disparity.b});
    // Written only when present, so that files without distortion stay readable by older readers.
    for (const auto& [keyword, d] :
         {std::pair{"distortion_rgb ", calib.rgb_distortion}, std::pair{"distortion_depth ", calib.depth_distortion}})
        if (d.any()) out << keyword << numbers({d.k1, d.k2, d.p1, d.p2, d.k3});
    file.commit();
}

RGBDCalib kinectV1DefaultCalib() {
    RGBDCalib calib;
    calib.rgb = Intrinsics{640, 480, 525.f, 525.f, 319.5f, 239.5f};
    calib.depth = calib.rgb;
    calib.T_depth_rgb = Mat4f::identity();
    calib.disparity = DisparityCalib::affine(0.001f, 0.f);
    return calib;
}

RGBDCalib tumCalib(int freiburg) {
    // Colour-camera intrinsics published with the TUM RGB-D benchmark; the depth images are registered
    // to the colour camera, so both share them.
    Intrinsics k;
    switch (freiburg) {
        case 1:
            k = Intrinsics{640, 480, 517.3f, 516.5f, 318.6f, 255.3f};
            break;
        case 2:
            k = Intrinsics{640, 480, 520.9f, 521.0f, 325.1f, 249.7f};
            break;
        case 3:
            k = Intrinsics{640, 480, 535.4f, 539.2f, 320.1f, 247.6f};
            break;
        default:
            throw ConfigError("tumCalib: the TUM sequences come from freiburg 1, 2 or 3, got " +
                              std::to_string(freiburg));
    }
    RGBDCalib calib;
    calib.rgb = k;
    calib.depth = k;
    calib.T_depth_rgb = Mat4f::identity();
    calib.disparity = DisparityCalib::affine(0.0002f, 0.f);  // PNG value / 5000
    return calib;
}

}  // namespace voxfuse
