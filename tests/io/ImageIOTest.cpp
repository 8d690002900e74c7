#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "IoTestUtil.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/FrameFolderSource.h"
#include "voxfuse/io/ImageIO.h"

namespace voxfuse {
namespace {

using test::makeDepth;
using test::makeRgb;
using test::readBytes;
using test::samePixels;
using test::ScratchDir;
using test::writeBytes;

std::string bytesOf(std::initializer_list<int> values) {
    std::string s;
    for (int v : values) s += char(v);
    return s;
}

// Expects `read` to throw IoError for `path` whose reason contains `reason_part`.
template <typename Read>
void expectIoError(Read read, const std::string& path, const std::string& reason_part) {
    try {
        read(path);
        ADD_FAILURE() << "no IoError for " << path << " (expected '" << reason_part << "')";
    } catch (const IoError& e) {
        EXPECT_EQ(e.file(), path);
        EXPECT_NE(e.reason().find(reason_part), std::string::npos) << "reason: " << e.reason();
    }
}

TEST(ImageIO, PpmWriteReadRoundTripIsByteExact) {
    ScratchDir dir;
    const Image<Vec4u8> rgb = makeRgb({5, 3}, 2);
    const std::string path = dir.file("a.ppm");
    writePPM(path, rgb);

    std::string expected = "P6\n5 3\n255\n";
    for (std::size_t i = 0; i < rgb.pixelCount(); ++i)
        expected += bytesOf({rgb.host()[i].x, rgb.host()[i].y, rgb.host()[i].z});
    EXPECT_EQ(readBytes(path), expected);

    const Image<Vec4u8> back = readPPM(path);
    EXPECT_TRUE(samePixels(rgb, back));
    const std::string again = dir.file("b.ppm");
    writePPM(again, back);
    EXPECT_EQ(readBytes(path), readBytes(again));
}

TEST(ImageIO, Pgm16IsBigEndian) {
    ScratchDir dir;
    const std::string header = "P5\n2 2\n65535\n";
    const std::string pixels = bytesOf({0x12, 0x34, 0xAB, 0xCD, 0x00, 0x01, 0xFF, 0x00});
    const std::string by_hand = dir.file("hand.pgm");
    writeBytes(by_hand, header + pixels);

    const Image<std::uint16_t> depth = readPGM16(by_hand);
    ASSERT_EQ(depth.size(), (Vec2i{2, 2}));
    EXPECT_EQ(depth.at(0, 0), 0x1234);
    EXPECT_EQ(depth.at(1, 0), 0xABCD);
    EXPECT_EQ(depth.at(0, 1), 0x0001);
    EXPECT_EQ(depth.at(1, 1), 0xFF00);

    const std::string written = dir.file("written.pgm");
    writePGM16(written, depth);
    EXPECT_EQ(readBytes(written), header + pixels);
}

// Samples above the maxval the header declares are no measurement: read as 0, and counted.
TEST(ImageIO, Pgm16SamplesAboveMaxvalReadAsNoMeasurement) {
    ScratchDir dir;
    const std::string path = dir.file("over.pgm");
    writeBytes(path, "P5\n2 2\n1000\n" + bytesOf({0x01, 0xF4, 0x03, 0xE8, 0x03, 0xE9, 0xFF, 0xFF}));
    Image<std::uint16_t> depth;
    EXPECT_EQ(readPGM16(path, depth), 2u);
    EXPECT_EQ(depth.at(0, 0), 500);
    EXPECT_EQ(depth.at(1, 0), 1000);  // maxval itself is valid
    EXPECT_EQ(depth.at(0, 1), 0);
    EXPECT_EQ(depth.at(1, 1), 0);
}

TEST(ImageIO, Pgm16RoundTrip) {
    ScratchDir dir;
    const Image<std::uint16_t> depth = makeDepth({7, 4}, 40);  // values above 255 exercise both bytes
    const std::string path = dir.file("d.pgm");
    writePGM16(path, depth);
    EXPECT_TRUE(samePixels(depth, readPGM16(path)));
}

TEST(ImageIO, NetpbmHeaderCommentsAndWhitespace) {
    ScratchDir dir;
    const std::string path = dir.file("comments.ppm");
    writeBytes(path,
               "P6 # a comment right after the magic\n# another\n  2\t1 # size\n255\n" + bytesOf({1, 2, 3, 4, 5, 6}));
    const Image<Vec4u8> rgb = readPPM(path);
    ASSERT_EQ(rgb.size(), (Vec2i{2, 1}));
    EXPECT_EQ(rgb.at(1, 0).x, 4);
    EXPECT_EQ(rgb.at(1, 0).z, 6);
    EXPECT_EQ(rgb.at(1, 0).w, 255);
}

TEST(ImageIO, PpmWithSmallMaxvalIsRescaled) {
    ScratchDir dir;
    const std::string path = dir.file("maxval15.ppm");
    writeBytes(path, "P6\n1 1\n15\n" + bytesOf({0, 15, 8}));
    const Image<Vec4u8> rgb = readPPM(path);
    EXPECT_EQ(rgb.at(0, 0).x, 0);
    EXPECT_EQ(rgb.at(0, 0).y, 255);
    EXPECT_EQ(rgb.at(0, 0).z, 136);
}

// Colour samples above the maxval are invalid too: read as full intensity (not wrapped), and counted.
TEST(ImageIO, PpmSamplesAboveMaxvalAreClampedAndCounted) {
    ScratchDir dir;
    const std::string path = dir.file("over.ppm");
    writeBytes(path, "P6\n2 1\n15\n" + bytesOf({16, 15, 200, 0, 3, 15}));
    Image<Vec4u8> rgb;
    EXPECT_EQ(readPPM(path, rgb), 2u);  // 16 and 200; 15 is maxval itself
    EXPECT_EQ(rgb.at(0, 0).x, 255);
    EXPECT_EQ(rgb.at(0, 0).z, 255);
    EXPECT_EQ(rgb.at(1, 0).y, 51);
    EXPECT_EQ(readColorImage(path, rgb), 2u);
}

TEST(ImageIO, BadNetpbmFilesGiveReasons) {
    ScratchDir dir;
    struct Case {
        const char* name;
        std::string bytes;
        bool depth;  // readPGM16 rather than readPPM
        const char* reason_part;
    };
    const std::vector<Case> cases = {
        {"truncated.ppm", "P6\n2 2\n255\n" + std::string(11, 'x'), false,
         "truncated: 2x2 needs 12 bytes of pixel data, the file has 11"},
        {"truncated.pgm", "P5\n2 2\n65535\n" + std::string(7, 'x'), true, "truncated: 2x2 needs 8 bytes"},
        {"no_data.ppm", "P6\n2 2\n255", false, "truncated"},
        {"huge.ppm", "P6\n100000 100000\n255\n" + std::string(10, 'x'), false, "truncated"},
        {"ascii.ppm", "P3\n1 1\n255\n1 2 3\n", false, "wrong magic 'P3': expected 'P6'"},
        {"color_as_depth.pgm", "P6\n1 1\n255\n" + std::string(3, 'x'), true, "wrong magic 'P6': expected 'P5'"},
        {"png_as_ppm.ppm", "\x89PNG\r\n\x1a\n", false, "wrong magic"},
        {"empty.ppm", "", false, "wrong magic: the file is too short"},
        {"bad_width.ppm", "P6\nx 2\n255\n", false, "bad header: expected the width"},
        {"bad_height.ppm", "P6\n2 2y\n255\n", false, "bad header: unexpected character 'y' after the height"},
        {"header_ends.pgm", "P5\n2 2\n", true, "bad header: file ends before the maxval"},
        {"zero_width.ppm", "P6\n0 2\n255\n", false, "width and height must be positive"},
        {"maxval_zero.ppm", "P6\n1 1\n0\n" + std::string(3, 'x'), false, "maxval 0 out of range"},
        {"maxval_16bit.ppm", "P6\n1 1\n65535\n" + std::string(6, 'x'), false, "maxval 65535 out of range"},
        {"maxval_zero.pgm", "P5\n1 1\n0\n" + std::string(2, 'x'), true, "maxval 0 out of range"},
        {"maxval_big.pgm", "P5\n1 1\n70000\n" + std::string(2, 'x'), true, "maxval 70000 out of range"},
        {"8bit.pgm", "P5\n1 1\n255\n" + std::string(1, 'x'), true,
         "8-bit PGM (maxval 255): expected a 16-bit depth PGM"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const std::string path = dir.file(c.name);
        writeBytes(path, c.bytes);
        if (c.depth)
            expectIoError([](const std::string& p) { readPGM16(p); }, path, c.reason_part);
        else
            expectIoError([](const std::string& p) { readPPM(p); }, path, c.reason_part);
    }
}

TEST(ImageIO, MissingFilesSayNoSuchFile) {
    const std::string path = "/nonexistent/voxfuse/image";
    expectIoError([](const std::string& p) { readPPM(p); }, path + ".ppm", "no such file");
    expectIoError([](const std::string& p) { readPGM16(p); }, path + ".pgm", "no such file");
    expectIoError([](const std::string& p) { readColorImage(p); }, path + ".png", "no such file");
    expectIoError([](const std::string& p) { readDepthPNG(p); }, path + ".png", "no such file");
}

TEST(ImageIO, PngColorRoundTrip) {
    ScratchDir dir;
    const Image<Vec4u8> rgb = makeRgb({6, 4}, 1);
    const std::string path = dir.file("c.png");
    writePNG(path, rgb);
    EXPECT_TRUE(samePixels(rgb, readColorImage(path)));

    Image<Vec4u8> translucent = makeRgb({3, 2}, 3);
    translucent.at(1, 1).w = 17;
    const std::string alpha_path = dir.file("alpha.png");
    writePNG(alpha_path, translucent);
    EXPECT_TRUE(samePixels(translucent, readColorImage(alpha_path)));
}

TEST(ImageIO, PngDepthRoundTrip) {
    ScratchDir dir;
    const Image<std::uint16_t> depth = makeDepth({9, 5}, 50);
    const std::string path = dir.file("d.png");
    writeDepthPNG(path, depth);
    EXPECT_TRUE(samePixels(depth, readDepthPNG(path)));
}

// Reading into an image reuses its memory when the size is the file's, and resizes it when not: the
// per-thread decode buffers never leak one file's pixels into another's image.
TEST(ImageIO, ReadingIntoAnImageReusesItsMemoryOnlyAtTheSameSize) {
    ScratchDir dir;
    const std::string small_png = dir.file("small.png"), large_png = dir.file("large.png"),
                      small_ppm = dir.file("small.ppm");
    const std::string small_depth = dir.file("small_d.png"), large_depth = dir.file("large_d.pgm");
    writePNG(small_png, makeRgb({6, 4}, 1));
    writePNG(large_png, makeRgb({9, 7}, 2));
    writePPM(small_ppm, makeRgb({6, 4}, 3));
    writeDepthPNG(small_depth, makeDepth({6, 4}, 4));
    writePGM16(large_depth, makeDepth({9, 7}, 5));

    Image<Vec4u8> rgb;
    readColorImage(small_png, rgb);
    const Vec4u8* memory = rgb.host();
    readColorImage(small_ppm, rgb);
    EXPECT_EQ(rgb.host(), memory);
    EXPECT_TRUE(samePixels(rgb, makeRgb({6, 4}, 3)));
    readColorImage(large_png, rgb);
    EXPECT_TRUE(samePixels(rgb, makeRgb({9, 7}, 2)));
    readColorImage(small_png, rgb);
    EXPECT_TRUE(samePixels(rgb, makeRgb({6, 4}, 1)));

    Image<std::uint16_t> depth;
    readDepthPNG(small_depth, depth);
    readPGM16(large_depth, depth);
    EXPECT_TRUE(samePixels(depth, makeDepth({9, 7}, 5)));
    readDepthPNG(small_depth, depth);
    EXPECT_TRUE(samePixels(depth, makeDepth({6, 4}, 4)));
}

TEST(ImageIO, GreyImageBecomesRgba) {
    ScratchDir dir;
    const std::string path = dir.file("grey.pgm");  // 8-bit PGM: through the general decoder, not readPPM
    writeBytes(path, "P5\n2 1\n255\n" + bytesOf({10, 200}));
    const Image<Vec4u8> rgba = readColorImage(path);
    ASSERT_EQ(rgba.size(), (Vec2i{2, 1}));
    EXPECT_EQ(rgba.at(1, 0).x, 200);
    EXPECT_EQ(rgba.at(1, 0).y, 200);
    EXPECT_EQ(rgba.at(1, 0).z, 200);
    EXPECT_EQ(rgba.at(1, 0).w, 255);
}

TEST(ImageIO, CorruptPngIsAnIoError) {
    ScratchDir dir;
    const std::string garbage = dir.file("garbage.png");
    writeBytes(garbage, "this is not a png at all");
    expectIoError([](const std::string& p) { readColorImage(p); }, garbage, "cannot decode image");
    expectIoError([](const std::string& p) { readDepthPNG(p); }, garbage, "cannot decode image");

    // A real PNG cut in half: the header is valid, the data is not.
    const std::string whole = dir.file("whole.png");
    writeDepthPNG(whole, makeDepth({64, 64}, 3));
    const std::string bytes = readBytes(whole);
    const std::string truncated = dir.file("truncated.png");
    writeBytes(truncated, bytes.substr(0, bytes.size() / 2));
    expectIoError([](const std::string& p) { readDepthPNG(p); }, truncated, "cannot decode image");
}

// A damaged JPEG decodes into a partly grey image with only libjpeg's warning on stderr, unless the
// warning is taken for the error it is.
TEST(ImageIO, DamagedJpegIsAnErrorNamingTheFile) {
    ScratchDir dir;
    const std::string good = dir.file("good.jpg");
    cv::Mat bgr(48, 64, CV_8UC3);
    cv::randu(bgr, cv::Scalar::all(0), cv::Scalar::all(255));
    ASSERT_TRUE(cv::imwrite(good, bgr));
    const Image<Vec4u8> whole = readColorImage(good);
    EXPECT_EQ(whole.size(), (Vec2i{64, 48}));

    const std::string bytes = readBytes(good);
    const std::string truncated = dir.file("truncated.jpg");
    writeBytes(truncated, bytes.substr(0, bytes.size() * 2 / 3));
    expectIoError([](const std::string& p) { readColorImage(p); }, truncated, "corrupt JPEG");

    std::string garbled = bytes;
    for (std::size_t i = garbled.size() / 2; i < garbled.size() / 2 + 16; ++i) garbled[i] = char(0xff);
    const std::string garbled_path = dir.file("garbled.jpg");
    writeBytes(garbled_path, garbled);
    expectIoError([](const std::string& p) { readColorImage(p); }, garbled_path, "corrupt JPEG");

    const std::string header_only = dir.file("header_only.jpg");
    writeBytes(header_only, bytes.substr(0, 4));
    expectIoError([](const std::string& p) { readColorImage(p); }, header_only, "corrupt JPEG");
}

TEST(ImageIO, ADamagedJpegColorFrameNamesItsFileAndFrameAndTheSequenceGoesOn) {
    ScratchDir dir;
    cv::Mat bgr(3, 4, CV_8UC3, cv::Scalar(10, 20, 30));
    for (int number : {0, 1, 2}) {
        char stem[32];
        std::snprintf(stem, sizeof stem, "frame-%06d", number);
        writeDepthPNG(dir.file(std::string(stem) + ".depth.png"), makeDepth({4, 3}, number));
        ASSERT_TRUE(cv::imwrite(dir.file(std::string(stem) + ".color.jpg"), bgr));
    }
    writeBytes(dir.file("intrinsics.K.txt"), "5 0 1.5\n0 5 1\n0 0 1\n");
    const std::string damaged = dir.file("frame-000001.color.jpg");
    const std::string bytes = readBytes(damaged);
    writeBytes(damaged, bytes.substr(0, bytes.size() / 2));

    FrameFolderSource source(dir.path());
    RGBDFrame frame;
    ASSERT_TRUE(source.next(frame));
    try {
        source.next(frame);
        FAIL() << "a damaged JPEG was decoded";
    } catch (const IoError& e) {
        EXPECT_EQ(e.file(), damaged);
        EXPECT_EQ(e.frame(), 1);
        EXPECT_NE(std::string(e.what()).find(damaged + ": frame 1: corrupt JPEG"), std::string::npos) << e.what();
    }
    ASSERT_TRUE(source.next(frame));
    EXPECT_EQ(frame.index, 2);
}

// Found by fuzzing: a PPM header in a file of another name went to a decoder (OpenCV's then), which
// allocated the 3 GB it claimed before reading a pixel.
TEST(ImageIO, OnlyKnownFormatsOfAPlausibleSizeReachTheDecoders) {
    ScratchDir dir;
    const std::string bomb = dir.file("colour.jpg");
    writeBytes(bomb, "P6\n224111\n4520\n56\n");
    expectIoError([](const std::string& p) { readColorImage(p); }, bomb, "the PPM/PGM says it is 224111x4520 pixels");
    const std::string short_pgm = dir.file("labels.png");
    writeBytes(short_pgm, "P5\n64 48\n255\n" + std::string(100, '\0'));
    expectIoError([](const std::string& p) { readLabelImage(p, -1); }, short_pgm, "truncated: a 64x48 PPM/PGM needs");
    const std::string gif = dir.file("colour.png");
    writeBytes(gif, "GIF89a\x01\x00\x01\x00\x00\x00\x00;");
    expectIoError([](const std::string& p) { readColorImage(p); }, gif, "not a format VoxFuse reads");
    const std::string tiff = dir.file("labels.tif");  // one directory: width 70000, height 70000
    std::string t = std::string("II*\0\x08\0\0\0", 8) + std::string("\x02\0", 2);
    t += std::string("\x00\x01\x04\x00\x01\x00\x00\x00\x70\x11\x01\x00", 12);
    t += std::string("\x01\x01\x04\x00\x01\x00\x00\x00\x70\x11\x01\x00", 12);
    writeBytes(tiff, t);
    expectIoError([](const std::string& p) { readLabelImage(p, -1); }, tiff, "the TIFF says it is 70000x70000 pixels");
    // A JPEG whose frame header (20000x20000) comes after 6 KB of comment: its size is found past the
    // head the other formats are read from.
    const std::string jpeg = dir.file("depth.png");
    std::string j = "\xff\xd8";
    const std::string comment(6000, 'c');
    j += std::string("\xff\xfe", 2) + char((comment.size() + 2) >> 8) + char((comment.size() + 2) & 0xff) + comment;
    j += std::string("\xff\xc0\x00\x0b\x08\x4e\x20\x4e\x20\x01\x01\x11\x00", 13);
    writeBytes(jpeg, j);
    expectIoError([](const std::string& p) { readLabelImage(p, -1); }, jpeg, "the JPEG says it is 20000x20000 pixels");
}

TEST(ImageIO, AFolderForAnImageSaysSo) {
    ScratchDir dir;
    expectIoError([](const std::string& p) { readColorImage(p); }, dir.path(), "is a folder, not an image file");
    expectIoError([](const std::string& p) { readPGM16(p); }, dir.path(), "is a folder, not an image file");
}

TEST(ImageIO, APngClaimingAHugeSizeIsRefusedBeforeDecoding) {
    ScratchDir dir;
    const std::string path = dir.file("huge.png");
    writePNG(path, makeRgb({4, 4}, 0));
    std::string bytes = readBytes(path);
    bytes[16] = bytes[20] = char(0x7f);  // width and height near 2^31 (the IHDR's CRC no longer matches either)
    writeBytes(path, bytes);
    expectIoError([](const std::string& p) { readColorImage(p); }, path, "too large for an image of a frame");
}

// A file is read whole before it is decoded: one larger than any frame's image is refused unread. The
// file is sparse, so it takes no disk.
TEST(ImageIO, AFileLargerThanAnyFrameImageIsRefusedUnread) {
    ScratchDir dir;
    for (const char* name : {"big.png", "big.ppm", "big.pgm"}) {
        SCOPED_TRACE(name);
        const std::string path = dir.file(name);
        if (std::string(name) == "big.png")
            writePNG(path, makeRgb({4, 4}, 0));
        else if (std::string(name) == "big.ppm")
            writePPM(path, makeRgb({4, 4}, 0));
        else
            writePGM16(path, makeDepth({4, 4}, 0));
        std::filesystem::resize_file(path, (std::uintmax_t(1) << 30) + 1);
        const auto read = [](const std::string& p) {
            if (p.size() > 4 && p.substr(p.size() - 4) == ".pgm")
                readPGM16(p);
            else
                readColorImage(p);
        };
        expectIoError(read, path, "too large for an image of a frame (at most 1 GiB)");
    }
}

TEST(ImageIO, EightBitPngAsDepthIsRejected) {
    ScratchDir dir;
    const std::string path = dir.file("colour.png");
    writePNG(path, makeRgb({4, 4}, 0));
    expectIoError([](const std::string& p) { readDepthPNG(p); }, path,
                  "expected a 16-bit single-channel depth PNG, got 8-bit 3-channel");
}

TEST(ImageIO, WriteErrors) {
    ScratchDir dir;
    EXPECT_THROW(writeDepthPNG(dir.file("depth.jpg"), makeDepth({2, 2}, 0)), IoError);
    EXPECT_THROW(writePNG("/nonexistent/voxfuse/c.png", makeRgb({2, 2}, 0)), IoError);
    EXPECT_THROW(writePPM("/nonexistent/voxfuse/c.ppm", makeRgb({2, 2}, 0)), IoError);
    EXPECT_THROW(writePGM16(dir.file("empty.pgm"), Image<std::uint16_t>()), IoError);
    EXPECT_THROW(writePNG(dir.file("empty.png"), Image<Vec4u8>()), IoError);
}

}  // namespace
}  // namespace voxfuse

// ---------------------------------------------------------------------------------------------
// Label images (readLabelImage)

namespace voxfuse {
namespace {

TEST(ImageIO, LabelImageEightBitIdsWithIgnoreId) {
    ScratchDir dir;
    // An 8-bit PGM, single-channel 8-bit: ids 0, 3, 254, 255.
    const std::string path = dir.file("labels.pgm");
    writeBytes(path, "P5\n2 2\n255\n" + bytesOf({0, 3, 254, 255}));
    const Image<ClassId> ignoring_zero = readLabelImage(path, 0);
    ASSERT_EQ(ignoring_zero.size(), (Vec2i{2, 2}));
    EXPECT_EQ(ignoring_zero.at(0, 0), kNoLabel);
    EXPECT_EQ(ignoring_zero.at(1, 0), 3);
    EXPECT_EQ(ignoring_zero.at(0, 1), 254);
    EXPECT_EQ(ignoring_zero.at(1, 1), 255);  // an ordinary class unless it is the ignore id
    const Image<ClassId> ignoring_none = readLabelImage(path, -1);
    EXPECT_EQ(ignoring_none.at(0, 0), 0);
    EXPECT_EQ(readLabelImage(path, 255).at(1, 1), kNoLabel);
}

TEST(ImageIO, LabelImageSixteenBitIdsAnd65535IsNoLabel) {
    ScratchDir dir;
    Image<std::uint16_t> ids({3, 1});
    ids.at(0, 0) = 1000;
    ids.at(1, 0) = 65535;
    ids.at(2, 0) = 7;
    const std::string path = dir.file("labels16.png");
    writeDepthPNG(path, ids);
    const Image<ClassId> labels = readLabelImage(path, 7);
    ASSERT_EQ(labels.size(), (Vec2i{3, 1}));
    EXPECT_EQ(labels.at(0, 0), 1000);
    EXPECT_EQ(labels.at(1, 0), kNoLabel);
    EXPECT_EQ(labels.at(2, 0), kNoLabel);  // the ignore id
    EXPECT_EQ(readLabelImage(path, -1).at(2, 0), 7);
}

TEST(ImageIO, LabelImagesKeepTheirIdsWhereDecodersWouldRescale) {
    ScratchDir dir;
    // A PGM whose maxval is the largest class: decoders stretch it to 0..255, the ids must stay.
    const std::string pgm = dir.file("few_classes.pgm");
    writeBytes(pgm, "P5\n3 1\n20\n" + bytesOf({0, 7, 20}));
    const Image<ClassId> from_pgm = readLabelImage(pgm, -1);
    EXPECT_EQ(from_pgm.at(1, 0), 7);
    EXPECT_EQ(from_pgm.at(2, 0), 20);
    // A 16-bit PGM (big-endian samples).
    const std::string pgm16 = dir.file("many_classes.pgm");
    writeBytes(pgm16, "P5\n2 1\n1000\n" + bytesOf({0x03, 0xE7, 0x00, 0x05}));
    const Image<ClassId> from_pgm16 = readLabelImage(pgm16, -1);
    EXPECT_EQ(from_pgm16.at(0, 0), 999);
    EXPECT_EQ(from_pgm16.at(1, 0), 5);
    // A 1-bit PNG, as binary masks are often saved: libpng expands 1 to 255.
    const std::string mask = dir.file("mask.png");
    cv::Mat bits(2, 8, CV_8UC1, cv::Scalar(0));
    bits.at<std::uint8_t>(1, 3) = 1;
    ASSERT_TRUE(cv::imwrite(mask, bits, {cv::IMWRITE_PNG_BILEVEL, 1}));
    std::ifstream png(mask, std::ios::binary);
    char head[26] = {};
    png.read(head, sizeof head);
    ASSERT_EQ(int(head[24]), 1) << "the test needs a 1-bit PNG";
    const Image<ClassId> from_mask = readLabelImage(mask, 0);
    EXPECT_EQ(from_mask.at(3, 1), 1);
    EXPECT_EQ(from_mask.at(2, 1), kNoLabel);
}

TEST(ImageIO, LabelImageErrors) {
    ScratchDir dir;
    const auto read = [](const std::string& p) { readLabelImage(p, 0); };
    const std::string color = dir.file("colour.png");
    writePNG(color, makeRgb({4, 4}, 1));
    expectIoError(read, color, "label images must be single-channel 8- or 16-bit class ids; this one has 3 channels");
    expectIoError(read, dir.file("missing.png"), "no such file");
    const std::string garbage = dir.file("garbage.png");
    writeBytes(garbage, "not a png at all");
    expectIoError(read, garbage, "cannot decode image");
    EXPECT_THROW(readLabelImage(garbage, 65536), ConfigError);
    EXPECT_THROW(readLabelImage(garbage, -2), ConfigError);
}

}  // namespace
}  // namespace voxfuse
