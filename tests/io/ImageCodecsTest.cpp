// The image codecs (src/io/ImageCodecs.h) against OpenCV's, an independent implementation: the files
// OpenCV writes in each format decode to the pixels OpenCV decodes from them, and the PNGs VoxFuse
// writes decode in OpenCV to the image written. Formats OpenCV does not write (CMYK JPEG, BMP with
// channel masks, palette BMP) are made by hand or by TurboJPEG.

#include <gtest/gtest.h>

#include <cstdint>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <turbojpeg.h>
#include <vector>

#include "IoTestUtil.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/FrameUndistorter.h"
#include "voxfuse/io/ImageIO.h"

namespace voxfuse {
namespace {

using test::makeDepth;
using test::makeRgb;
using test::samePixels;
using test::ScratchDir;
using test::writeBytes;

cv::Mat randomImage(int rows, int cols, int type, int seed) {
    cv::Mat m(rows, cols, type);
    cv::RNG rng{std::uint64_t(seed)};
    rng.fill(m, cv::RNG::UNIFORM, 0, CV_MAT_DEPTH(type) == CV_16U ? 65536 : 256);
    return m;
}

// The largest difference, over every channel, between our RGBA and OpenCV's BGR(A) or grey decoding.
int largestDifference(const Image<Vec4u8>& rgba, const cv::Mat& opencv) {
    cv::Mat expected;
    const int channels = opencv.channels();
    cv::cvtColor(opencv, expected,
                 channels == 1   ? cv::COLOR_GRAY2RGBA
                 : channels == 3 ? cv::COLOR_BGR2RGBA
                                 : cv::COLOR_BGRA2RGBA);
    EXPECT_EQ(rgba.size(), (Vec2i{expected.cols, expected.rows}));
    int worst = 0;
    for (int y = 0; y < expected.rows; ++y)
        for (int x = 0; x < expected.cols; ++x) {
            const cv::Vec4b e = expected.at<cv::Vec4b>(y, x);
            const Vec4u8 a = rgba.at(x, y);
            worst = std::max(
                {worst, std::abs(a.x - e[0]), std::abs(a.y - e[1]), std::abs(a.z - e[2]), std::abs(a.w - e[3])});
        }
    return worst;
}

TEST(ImageCodecs, ColourFilesDecodeAsOpenCVDecodesThem) {
    ScratchDir dir;
    const cv::Mat bgr = randomImage(37, 53, CV_8UC3, 1);  // odd sizes: BMP rows are padded, JPEG blocks partial
    const cv::Mat bgra = randomImage(37, 53, CV_8UC4, 2);
    const cv::Mat grey = randomImage(37, 53, CV_8UC1, 3);
    const cv::Mat bgr16 = randomImage(37, 53, CV_16UC3, 4);
    struct Case {
        const char* name;
        const cv::Mat& image;
    };
    for (const Case& c :
         {Case{"rgb.png", bgr}, Case{"rgba.png", bgra}, Case{"grey.png", grey}, Case{"rgb16.png", bgr16},
          Case{"rgb.tif", bgr}, Case{"rgba.tif", bgra}, Case{"grey.tif", grey}, Case{"rgb16.tif", bgr16},
          Case{"rgb.bmp", bgr}, Case{"grey.bmp", grey}, Case{"grey.pgm", grey}, Case{"rgb.jpg", bgr},
          Case{"grey.jpg", grey}}) {
        SCOPED_TRACE(c.name);
        const std::string path = dir.file(c.name);
        ASSERT_TRUE(cv::imwrite(path, c.image));
        cv::Mat decoded = cv::imread(path, cv::IMREAD_UNCHANGED);
        ASSERT_FALSE(decoded.empty());
        if (decoded.depth() == CV_16U) decoded.convertTo(decoded, CV_8U, 1.0 / 257.0);
        EXPECT_EQ(largestDifference(readColorImage(path), decoded), 0);
    }
}

TEST(ImageCodecs, SixteenBitDepthAndLabelFilesKeepEverySample) {
    ScratchDir dir;
    const cv::Mat depth = randomImage(29, 41, CV_16UC1, 5);
    const cv::Mat ids = randomImage(29, 41, CV_8UC1, 6);
    for (const char* name : {"depth.png", "depth.tif"}) {
        SCOPED_TRACE(name);
        const std::string path = dir.file(name);
        ASSERT_TRUE(cv::imwrite(path, depth));
        const Image<std::uint16_t> read = readDepthPNG(path);
        ASSERT_EQ(read.size(), (Vec2i{41, 29}));
        int wrong = 0;
        for (int y = 0; y < 29; ++y)
            for (int x = 0; x < 41; ++x) wrong += read.at(x, y) != depth.at<std::uint16_t>(y, x);
        EXPECT_EQ(wrong, 0);
        const Image<ClassId> labels = readLabelImage(path, -1);
        EXPECT_EQ(labels.at(7, 3), depth.at<std::uint16_t>(3, 7) == 65535 ? kNoLabel : depth.at<std::uint16_t>(3, 7));
    }
    for (const char* name : {"ids.png", "ids.tif", "ids.bmp", "ids.pgm"}) {
        SCOPED_TRACE(name);
        const std::string path = dir.file(name);
        ASSERT_TRUE(cv::imwrite(path, ids));
        const Image<ClassId> labels = readLabelImage(path, -1);
        int wrong = 0;
        for (int y = 0; y < 29; ++y)
            for (int x = 0; x < 41; ++x) wrong += labels.at(x, y) != ids.at<std::uint8_t>(y, x);
        EXPECT_EQ(wrong, 0);
    }
}

TEST(ImageCodecs, ThePngsVoxFuseWritesDecodeInOpenCVToTheImageWritten) {
    ScratchDir dir;
    Image<Vec4u8> rgba = makeRgb({31, 17}, 7);
    const std::string opaque = dir.file("opaque.png");
    writePNG(opaque, rgba);
    const cv::Mat bgr = cv::imread(opaque, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(bgr.type(), CV_8UC3) << "an opaque image is written as RGB";
    EXPECT_EQ(largestDifference(rgba, bgr), 0);

    rgba.at(3, 4).w = 99;
    const std::string translucent = dir.file("translucent.png");
    writePNG(translucent, rgba);
    const cv::Mat bgra = cv::imread(translucent, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(bgra.type(), CV_8UC4);
    EXPECT_EQ(largestDifference(rgba, bgra), 0);

    const Image<std::uint16_t> depth = makeDepth({23, 19}, 8);
    const std::string depth_path = dir.file("depth.png");
    writeDepthPNG(depth_path, depth);
    const cv::Mat d = cv::imread(depth_path, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(d.type(), CV_16UC1);
    int wrong = 0;
    for (int y = 0; y < 19; ++y)
        for (int x = 0; x < 23; ++x) wrong += d.at<std::uint16_t>(y, x) != depth.at(x, y);
    EXPECT_EQ(wrong, 0);

    EXPECT_THROW(writePNG(dir.file("shot.jpg"), rgba), IoError) << "writePNG writes PNG files only";
}

std::string rgbaText(Vec4u8 c) {
    return std::to_string(c.x) + " " + std::to_string(c.y) + " " + std::to_string(c.z) + " " + std::to_string(c.w);
}

// A BMP: file header, 40-byte info header, then `extra` (masks, palette) and the rows, bottom up.
std::string bmpFile(int width, int height, int bits, std::uint32_t compression, const std::string& extra,
                    const std::string& rows, std::uint32_t palette_entries = 0) {
    const auto le32 = [](std::uint32_t v) {
        return std::string{char(v & 0xff), char((v >> 8) & 0xff), char((v >> 16) & 0xff), char(v >> 24)};
    };
    const auto le16 = [](std::uint16_t v) { return std::string{char(v & 0xff), char(v >> 8)}; };
    const std::uint32_t offset = 14 + 40 + std::uint32_t(extra.size());
    std::string f = "BM" + le32(offset + std::uint32_t(rows.size())) + le32(0) + le32(offset);
    f += le32(40) + le32(std::uint32_t(width)) + le32(std::uint32_t(height)) + le16(1) + le16(std::uint16_t(bits)) +
         le32(compression) + le32(std::uint32_t(rows.size())) + le32(2835) + le32(2835) + le32(palette_entries) +
         le32(0);
    return f + extra + rows;
}

TEST(ImageCodecs, BmpsWithChannelMasksAndColourPalettesDecode) {
    ScratchDir dir;
    // 2x1, 16-bit RGB565 (compression 3 with masks): pure red, then pure blue. Rows pad to 4 bytes.
    const auto mask = [](std::uint32_t v) {
        return std::string{char(v & 0xff), char((v >> 8) & 0xff), char((v >> 16) & 0xff), char(v >> 24)};
    };
    const std::string rgb565 = dir.file("565.bmp");
    writeBytes(rgb565,
               bmpFile(2, 1, 16, 3, mask(0xf800) + mask(0x07e0) + mask(0x001f), std::string("\x00\xf8\x1f\x00", 4)));
    const Image<Vec4u8> a = readColorImage(rgb565);
    ASSERT_EQ(a.size(), (Vec2i{2, 1}));
    EXPECT_EQ(rgbaText(a.at(0, 0)), "255 0 0 255");
    EXPECT_EQ(rgbaText(a.at(1, 0)), "0 0 255 255");

    // 3x2, 4-bit palette of two colours (so named in the header: 0 would mean all 16), bottom-up rows:
    // the top row is the file's second.
    const std::string palette = std::string("\x00\x00\xff\x00", 4) + std::string("\x00\xff\x00\x00", 4);
    const std::string rows = std::string("\x01\x00\x00\x00", 4) + std::string("\x10\x10\x00\x00", 4);
    const std::string four_bit = dir.file("palette.bmp");
    writeBytes(four_bit, bmpFile(3, 2, 4, 0, palette, rows, 2));
    const Image<Vec4u8> b = readColorImage(four_bit);
    ASSERT_EQ(b.size(), (Vec2i{3, 2}));
    EXPECT_EQ(rgbaText(b.at(0, 0)), "0 255 0 255");  // top row: entries 1, 0, 1
    EXPECT_EQ(rgbaText(b.at(1, 0)), "255 0 0 255");
    EXPECT_EQ(rgbaText(b.at(2, 0)), "0 255 0 255");
    EXPECT_EQ(rgbaText(b.at(1, 1)), "0 255 0 255");  // bottom row: entries 0, 1, 0
    EXPECT_EQ(rgbaText(b.at(0, 1)), "255 0 0 255");

    const std::string rle = dir.file("rle.bmp");
    writeBytes(rle, bmpFile(3, 2, 8, 1, std::string(8, '\0'), std::string(8, '\0')));
    EXPECT_THROW(readColorImage(rle), IoError);
    const std::string truncated = dir.file("truncated.bmp");
    writeBytes(truncated, bmpFile(3, 2, 4, 0, palette, rows.substr(0, 5), 2));
    try {
        readColorImage(truncated);
        FAIL() << "a truncated BMP was decoded";
    } catch (const IoError& e) {
        EXPECT_NE(e.reason().find("truncated BMP"), std::string::npos) << e.reason();
    }
}

TEST(ImageCodecs, CmykJpegsAreConvertedAsAdobeStoresThem) {
    ScratchDir dir;
    // Inverted inks as Adobe writes them: C = M = Y = 255 - ink, so R = C K / 255.
    const std::vector<unsigned char> cmyk{200, 100, 255, 128, 200, 100, 255, 128, 200, 100, 255, 128,
                                          200, 100, 255, 128, 200, 100, 255, 128, 200, 100, 255, 128,
                                          200, 100, 255, 128, 200, 100, 255, 128, 200, 100, 255, 128};
    const std::unique_ptr<void, int (*)(tjhandle)> tj(tjInitCompress(), tjDestroy);
    unsigned char* jpeg = nullptr;
    unsigned long size = 0;
    ASSERT_EQ(tjCompress2(tj.get(), cmyk.data(), 3, 0, 3, TJPF_CMYK, &jpeg, &size, TJSAMP_444, 100, 0), 0);
    const std::string path = dir.file("cmyk.jpg");
    writeBytes(path, std::string(reinterpret_cast<const char*>(jpeg), size));
    tjFree(jpeg);
    const Image<Vec4u8> rgb = readColorImage(path);
    ASSERT_EQ(rgb.size(), (Vec2i{3, 3}));
    // 200 * 128 / 255 = 100, 100 * 128 / 255 = 50, 255 * 128 / 255 = 128 (give or take the lossy coding)
    EXPECT_NEAR(rgb.at(1, 1).x, 100, 3);
    EXPECT_NEAR(rgb.at(1, 1).y, 50, 3);
    EXPECT_NEAR(rgb.at(1, 1).z, 128, 3);
}

// The undistortion maps and resampling against OpenCV's initUndistortRectifyMap and remap.
TEST(ImageCodecs, UndistortionResamplesAsOpenCVDoes) {
    const Intrinsics k{160, 120, 130.f, 131.f, 79.3f, 60.8f};
    const LensDistortion d{-0.25f, 0.08f, 0.001f, -0.0015f, 0.01f};
    RGBDCalib calib;
    calib.rgb = k;
    calib.depth = k;
    calib.rgb_distortion = d;
    calib.depth_distortion = d;
    const FrameUndistorter undistorter(calib);
    RGBDFrame frame;
    frame.rgb = makeRgb(k.size(), 9);
    frame.depth_raw = makeDepth(k.size(), 10);
    const Image<Vec4u8> raw_rgb = makeRgb(k.size(), 9);
    const Image<std::uint16_t> raw_depth = makeDepth(k.size(), 10);
    undistorter.apply(frame);

    const cv::Matx33d K(k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
    const cv::Vec<double, 5> coefficients(d.k1, d.k2, d.p1, d.p2, d.k3);
    cv::Mat map_x, map_y;
    cv::initUndistortRectifyMap(K, coefficients, cv::noArray(), K, cv::Size(k.width, k.height), CV_32FC1, map_x, map_y);
    const cv::Mat rgb_in(k.height, k.width, CV_8UC4, const_cast<Vec4u8*>(raw_rgb.host()));
    const cv::Mat depth_in(k.height, k.width, CV_16UC1, const_cast<std::uint16_t*>(raw_depth.host()));
    cv::Mat rgb_out, depth_out;
    cv::remap(rgb_in, rgb_out, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar::all(0));
    cv::remap(depth_in, depth_out, map_x, map_y, cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar(0));
    int colour_off_by_more_than_one = 0, depth_differs = 0;
    for (int y = 0; y < k.height; ++y)
        for (int x = 0; x < k.width; ++x) {
            const cv::Vec4b e = rgb_out.at<cv::Vec4b>(y, x);
            const Vec4u8 a = frame.rgb.at(x, y);
            // OpenCV's bilinear weights are quantised to 1/32 of a pixel: up to one level apart.
            colour_off_by_more_than_one += std::abs(a.x - e[0]) > 1 || std::abs(a.y - e[1]) > 1 ||
                                           std::abs(a.z - e[2]) > 1 || std::abs(a.w - e[3]) > 1;
            depth_differs += frame.depth_raw.at(x, y) != depth_out.at<std::uint16_t>(y, x);
        }
    // Colour differs by more only where a 1/32-pixel step crosses a sharp edge of the random image,
    // depth where a raw position is within rounding of a pixel boundary.
    EXPECT_LT(colour_off_by_more_than_one, k.width * k.height / 50);
    EXPECT_LT(depth_differs, k.width * k.height / 500);
}

}  // namespace
}  // namespace voxfuse
