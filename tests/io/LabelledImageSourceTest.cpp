#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "IoTestUtil.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/ImageIO.h"
#include "voxfuse/io/LabelledImageSource.h"

namespace voxfuse {
namespace {

using test::ScratchDir;
using test::writeBytes;
using Match = LabelStreamOptions::Match;

struct FakeFrame {
    int index;
    double timestamp_s;
    double rgb_timestamp_s = -1.0;
    long long file_number = -1;
};

// Frames with the given indices and timestamps, an 8x6 depth image each; the colour camera is 8x6 too
// unless `rgb_valid` is false (then only the depth camera is calibrated).
class FakeSource : public ImageSource {
public:
    explicit FakeSource(std::vector<FakeFrame> frames, bool rgb_valid = true) : frames_(std::move(frames)) {
        calib_.depth = Intrinsics{8, 6, 10.f, 10.f, 3.5f, 2.5f};
        if (rgb_valid) calib_.rgb = calib_.depth;
        ground_truth_.push_back(TimedPose{0.5, Mat4f::identity()});
    }
    // Frames 0..n-1, one every 1/30 s from t = 100.
    static std::unique_ptr<FakeSource> sequence(int n) {
        std::vector<FakeFrame> frames;
        for (int i = 0; i < n; ++i) frames.push_back({i, 100.0 + i / 30.0});
        return std::make_unique<FakeSource>(frames);
    }

    const RGBDCalib& calib() const override { return calib_; }
    bool next(RGBDFrame& frame) override {
        if (position_ >= frames_.size()) return false;
        const FakeFrame& f = frames_[position_++];
        frame.index = f.index;
        frame.timestamp_s = f.timestamp_s;
        frame.rgb_timestamp_s = f.rgb_timestamp_s;
        frame.file_number = f.file_number;
        frame.depth_raw.resize(calib_.depth.size());
        for (std::size_t i = 0; i < frame.depth_raw.pixelCount(); ++i) frame.depth_raw.host()[i] = 1000;
        return true;
    }
    int frameCount() const override { return int(frames_.size()); }
    std::string description() const override { return "fake source"; }
    const std::vector<TimedPose>& groundTruth() const override { return ground_truth_; }
    bool isLive() const override { return true; }

private:
    std::vector<FakeFrame> frames_;
    std::size_t position_ = 0;
    RGBDCalib calib_;
    std::vector<TimedPose> ground_truth_;
};

// A single-channel label image (CV_8U or CV_16U) filled with `id`.
void writeLabels(const std::string& path, int id, Vec2i size = {8, 6}, int type = CV_8UC1) {
    const cv::Mat m(size.y, size.x, type, cv::Scalar(id));
    ASSERT_TRUE(cv::imwrite(path, m)) << path;
}

LabelStreamOptions optionsFor(const std::string& path, Match match = Match::Automatic) {
    LabelStreamOptions options;
    options.path = path;
    options.match = match;
    return options;
}

// The id every pixel of the frame's labels has (the test images are uniform), -1 when it has no labels.
int uniformId(const RGBDFrame& frame) {
    if (frame.labels.empty()) return -1;
    const ClassId id = frame.labels.host()[0];
    for (std::size_t i = 0; i < frame.labels.pixelCount(); ++i)
        if (frame.labels.host()[i] != id) return -2;
    return id;
}

// Reads every frame, returning each one's uniform label id (-1 without labels).
std::vector<int> readIds(ImageSource& source) {
    std::vector<int> ids;
    RGBDFrame frame;  // reused, as the engine's callers do: stale labels must not survive
    while (source.next(frame)) ids.push_back(uniformId(frame));
    return ids;
}

template <typename Make>
void expectConstructionIoError(Make make, const std::string& path, const std::string& reason_part) {
    try {
        make();
        ADD_FAILURE() << "no IoError for " << path << " (expected '" << reason_part << "')";
    } catch (const IoError& e) {
        EXPECT_EQ(e.file(), path);
        EXPECT_NE(e.reason().find(reason_part), std::string::npos) << "reason: " << e.reason();
    }
}

TEST(LabelledImageSource, IndexMatchingOfNamesThatAreNotFrameNumbersUsesNaturalOrder) {
    ScratchDir dir;
    const std::string folder = dir.file("labels/");
    // Numbers far too sparse to be frame numbers: the images are taken in order, one per frame.
    writeLabels(folder + "shot_2.png", 2);
    writeLabels(folder + "shot_50000.png", 50);
    writeLabels(folder + "shot_1.png", 1);
    writeBytes(folder + "README.txt", "not an image, ignored");
    LabelledImageSource source(FakeSource::sequence(4), optionsFor(folder));
    EXPECT_EQ(source.match(), Match::Index);
    EXPECT_EQ(source.labelImageCount(), 3);
    EXPECT_EQ(readIds(source), (std::vector<int>{1, 2, 50, -1}));  // frame 3: no image left, labels cleared
    EXPECT_EQ(source.framesWithLabels(), 3);
    EXPECT_EQ(source.framesWithoutLabels(), 1);
    EXPECT_EQ(source.labelErrors(), 0);
}

TEST(LabelledImageSource, IndexMatchingFollowsFrameIndexNotPosition) {
    ScratchDir dir;
    for (int i : {0, 1, 2, 9, 10, 11}) writeLabels(dir.file(std::to_string(i) + ".png"), 50 + i);
    // A source that starts later and skips frames: the index decides, not the call count.
    LabelledImageSource source(std::make_unique<FakeSource>(std::vector<FakeFrame>{{2, 0.0}, {4, 0.1}, {9, 0.2}}),
                               optionsFor(dir.path()));
    EXPECT_EQ(source.match(), Match::Index);                     // whole numbers are not timestamps
    EXPECT_EQ(readIds(source), (std::vector<int>{52, -1, 59}));  // 3 to 8 have no image
}

TEST(LabelledImageSource, NumberedImagesKeepTheirFramesAcrossGaps) {
    ScratchDir dir;
    // A segmentation that skipped frame 2 (and 4): the frames after a gap keep their own images.
    for (int i : {0, 1, 3, 5})
        writeLabels(dir.file("zero/" + std::string(i < 10 ? "00000" : "0000") + std::to_string(i) + ".png"), 10 + i);
    LabelledImageSource from_zero(FakeSource::sequence(7), optionsFor(dir.file("zero")));
    EXPECT_EQ(from_zero.labelImageCount(), 4);
    EXPECT_EQ(readIds(from_zero), (std::vector<int>{10, 11, -1, 13, -1, 15, -1}));
    EXPECT_NE(from_zero.description().find("2 frames in between without one"), std::string::npos)
        << from_zero.description();
    // Numbered from 1, with a prefix: the smallest number goes with frame 0.
    for (int i : {1, 2, 4}) writeLabels(dir.file("one/frame-" + std::to_string(i) + ".png"), 20 + i);
    LabelledImageSource from_one(FakeSource::sequence(4), optionsFor(dir.file("one")));
    EXPECT_EQ(readIds(from_one), (std::vector<int>{21, 22, -1, 24}));
}

TEST(LabelledImageSource, NumberedImagesMeetFramesNumberedByTheirFilesByNumber) {
    // A frame folder whose files skip numbers (frame-000015, -17, ..., -25) and labels named after
    // them: frame 17 takes 17's image, not the second image or the one at 15 + its index.
    ScratchDir dir;
    std::vector<FakeFrame> frames;
    for (int i = 0; i < 6; ++i) {
        const int number = 15 + 2 * i;
        frames.push_back({i, number / 30.0, -1.0, number});
        if (number != 21)
            writeLabels(dir.file("labels/frame-0000" + std::to_string(number) + ".png"), number);  // 21 left out
    }
    LabelledImageSource source(std::make_unique<FakeSource>(frames), optionsFor(dir.file("labels")));
    EXPECT_EQ(source.match(), Match::Index);
    EXPECT_EQ(readIds(source), (std::vector<int>{15, 17, 19, -1, 23, 25}));
    // Labels numbered otherwise than the frames' files meet none of them, rather than the wrong ones.
    for (int i = 0; i < 6; ++i) writeLabels(dir.file("other/" + std::to_string(i) + ".png"), 40 + i);
    LabelledImageSource other(std::make_unique<FakeSource>(frames), optionsFor(dir.file("other")));
    EXPECT_EQ(readIds(other), (std::vector<int>{-1, -1, -1, -1, -1, -1}));
}

TEST(LabelledImageSource, EightAndSixteenBitIdsWithIgnoreIdAndNoLabel) {
    ScratchDir dir;
    cv::Mat eight(6, 8, CV_8UC1, cv::Scalar(3));
    eight.at<std::uint8_t>(0, 0) = 0;
    eight.at<std::uint8_t>(0, 1) = 255;
    ASSERT_TRUE(cv::imwrite(dir.file("0.png"), eight));
    cv::Mat sixteen(6, 8, CV_16UC1, cv::Scalar(1000));
    sixteen.at<std::uint16_t>(0, 0) = 0;
    sixteen.at<std::uint16_t>(0, 1) = 65535;
    ASSERT_TRUE(cv::imwrite(dir.file("1.png"), sixteen));

    for (const int ignore_id : {0, -1}) {
        SCOPED_TRACE("ignore id " + std::to_string(ignore_id));
        LabelStreamOptions options = optionsFor(dir.path());
        options.ignore_id = ignore_id;
        LabelledImageSource source(FakeSource::sequence(2), options);
        RGBDFrame frame;
        ASSERT_TRUE(source.next(frame));
        ASSERT_EQ(frame.labels.size(), (Vec2i{8, 6}));
        EXPECT_EQ(frame.labels.at(0, 0), ignore_id == 0 ? kNoLabel : ClassId(0));
        EXPECT_EQ(frame.labels.at(1, 0), 255);
        EXPECT_EQ(frame.labels.at(2, 0), 3);
        EXPECT_EQ(frame.labels_path, dir.file("0.png"));
        ASSERT_TRUE(source.next(frame));
        ASSERT_EQ(frame.labels.size(), (Vec2i{8, 6}));
        EXPECT_EQ(frame.labels.at(0, 0), ignore_id == 0 ? kNoLabel : ClassId(0));
        EXPECT_EQ(frame.labels.at(1, 0), kNoLabel);
        EXPECT_EQ(frame.labels.at(2, 0), 1000);
    }
}

TEST(LabelledImageSource, TimestampMatchingTakesNearestWithinTolerance) {
    ScratchDir dir;
    writeLabels(dir.file("100.000000.png"), 1);
    writeLabels(dir.file("100.033333.png"), 2);
    writeLabels(dir.file("100.066667.png"), 3);
    writeLabels(dir.file("99.500000.png"), 9);  // numeric order, not by name
    const std::vector<FakeFrame> frames{
        {0, 100.010},  // 0.010 from #1
        {1, 100.045},  // 0.012 from #2, 0.022 from #3
        {2, 100.060},  // 0.007 from #3
        {3, 100.090},  // 0.023 from #3: too far
        {4, 99.490},   // 0.010 from 99.5
        {5, 99.000},   // nothing near
    };
    LabelledImageSource source(std::make_unique<FakeSource>(frames), optionsFor(dir.path()));
    EXPECT_EQ(source.match(), Match::Timestamp);
    EXPECT_EQ(readIds(source), (std::vector<int>{1, 2, 3, -1, 9, -1}));
    EXPECT_EQ(source.framesWithLabels(), 4);
    EXPECT_EQ(source.framesWithoutLabels(), 2);

    // Where the source knows when the colour image was taken (TUM pairs depth with a colour image up
    // to 0.02 s apart), the labels, computed from colour, are matched to that time.
    LabelledImageSource by_color(std::make_unique<FakeSource>(std::vector<FakeFrame>{{0, 100.045, 100.064}}),
                                 optionsFor(dir.path()));
    EXPECT_EQ(readIds(by_color), (std::vector<int>{3}));

    // A wider tolerance lets frame 3 take #3.
    LabelStreamOptions wide = optionsFor(dir.path(), Match::Timestamp);
    wide.max_time_difference_s = 0.03;
    LabelledImageSource lenient(std::make_unique<FakeSource>(frames), wide);
    EXPECT_EQ(readIds(lenient), (std::vector<int>{1, 2, 3, 3, 9, -1}));
}

TEST(LabelledImageSource, ListFileWithRelativePaths) {
    ScratchDir dir;
    writeLabels(dir.file("seq/seg/a.png"), 11);
    writeLabels(dir.file("seq/seg/b.png"), 12);
    const std::string list = dir.file("seq/labels.txt");
    writeBytes(list,
               "# semantic labels\n"
               "# timestamp filename\n"
               "5.1 seg/b.png\n"
               "5.0 seg/a.png\n"
               "\n"
               "5.2 seg/missing.png\n");
    const std::vector<FakeFrame> frames{{0, 5.0}, {1, 5.1}, {2, 5.2}};
    LabelledImageSource source(std::make_unique<FakeSource>(frames), optionsFor(list));
    EXPECT_EQ(source.match(), Match::Timestamp);  // a list has timestamps
    EXPECT_EQ(source.labelImageCount(), 2);
    EXPECT_EQ(source.missingListedFiles(), 1);
    RGBDFrame frame;
    ASSERT_TRUE(source.next(frame));
    EXPECT_EQ(uniformId(frame), 11);
    EXPECT_EQ(frame.labels_path, dir.file("seq/seg/a.png"));  // relative to the list's folder, not the cwd
    ASSERT_TRUE(source.next(frame));
    EXPECT_EQ(uniformId(frame), 12);
    ASSERT_TRUE(source.next(frame));
    EXPECT_EQ(uniformId(frame), -1);
    EXPECT_TRUE(frame.labels_path.empty());
    EXPECT_NE(source.description().find("1 listed images not on disk"), std::string::npos) << source.description();

    // Index matching of a list follows the order listed; a missing file keeps its line's frame.
    LabelledImageSource by_index(std::make_unique<FakeSource>(frames), optionsFor(list, Match::Index));
    EXPECT_EQ(readIds(by_index), (std::vector<int>{12, 11, -1}));
    const std::string gap = dir.file("seq/gap.txt");
    writeBytes(gap, "0 seg/a.png\n0 seg/missing.png\n0 seg/b.png\n");
    LabelledImageSource across_gap(FakeSource::sequence(3), optionsFor(gap, Match::Index));
    EXPECT_EQ(across_gap.labelImageCount(), 2);
    EXPECT_EQ(readIds(across_gap), (std::vector<int>{11, -1, 12}));

    // A malformed line is an error naming the line.
    const std::string bad = dir.file("seq/bad.txt");
    writeBytes(bad, "5.0 seg/a.png\nseg/b.png\n");
    try {
        LabelledImageSource s(FakeSource::sequence(1), optionsFor(bad));
        ADD_FAILURE() << "no ParseError";
    } catch (const ParseError& e) {
        EXPECT_EQ(e.file(), bad);
        EXPECT_EQ(e.line(), 2);
    }
}

TEST(LabelledImageSource, AutomaticModeChoice) {
    ScratchDir dir;
    writeLabels(dir.file("whole/000001.png"), 1);
    writeLabels(dir.file("whole/000002.png"), 2);
    EXPECT_EQ(LabelledImageSource(FakeSource::sequence(1), optionsFor(dir.file("whole"))).match(), Match::Index);

    writeLabels(dir.file("stamps/1305031102.175304.png"), 1);
    writeLabels(dir.file("stamps/1305031102.211214.png"), 2);
    EXPECT_EQ(LabelledImageSource(FakeSource::sequence(1), optionsFor(dir.file("stamps"))).match(), Match::Timestamp);
    // Asked for, whole numbers are timestamps too.
    EXPECT_EQ(LabelledImageSource(FakeSource::sequence(1), optionsFor(dir.file("whole"), Match::Timestamp)).match(),
              Match::Timestamp);

    writeLabels(dir.file("mixed/1305031102.175304.png"), 1);
    writeLabels(dir.file("mixed/extra.png"), 2);
    const std::string mixed = dir.file("mixed");
    EXPECT_EQ(LabelledImageSource(FakeSource::sequence(1), optionsFor(mixed)).match(), Match::Index);
    expectConstructionIoError(
        [&] { LabelledImageSource s(FakeSource::sequence(1), optionsFor(mixed, Match::Timestamp)); }, mixed,
        "'extra.png' is not");
}

TEST(LabelledImageSource, LowerResolutionOfTheSameAspectIsAccepted) {
    ScratchDir dir;
    writeLabels(dir.file("0.png"), 4, {4, 3});  // half of the 8x6 colour camera
    writeLabels(dir.file("1.png"), 5, {16, 12});
    LabelledImageSource source(FakeSource::sequence(2), optionsFor(dir.path()));
    RGBDFrame frame;
    ASSERT_TRUE(source.next(frame));
    EXPECT_EQ(frame.labels.size(), (Vec2i{4, 3}));
    EXPECT_EQ(uniformId(frame), 4);
    ASSERT_TRUE(source.next(frame));
    EXPECT_EQ(frame.labels.size(), (Vec2i{16, 12}));

    // Without a calibrated colour camera the depth camera's aspect ratio counts.
    LabelledImageSource depth_only(std::make_unique<FakeSource>(std::vector<FakeFrame>{{0, 0.0}}, false),
                                   optionsFor(dir.path()));
    ASSERT_TRUE(depth_only.next(frame));
    EXPECT_EQ(frame.labels.size(), (Vec2i{4, 3}));
}

TEST(LabelledImageSource, WrongAspectRatioNamesFileAndFrame) {
    ScratchDir dir;
    writeLabels(dir.file("0.png"), 1);
    writeLabels(dir.file("1.png"), 1, {8, 8});
    writeLabels(dir.file("2.png"), 3);
    LabelledImageSource source(FakeSource::sequence(3), optionsFor(dir.path()));
    RGBDFrame frame;
    ASSERT_TRUE(source.next(frame));
    try {
        source.next(frame);
        ADD_FAILURE() << "no IoError for an 8x8 label image on an 8x6 camera";
    } catch (const IoError& e) {
        EXPECT_EQ(e.file(), dir.file("1.png"));
        EXPECT_EQ(e.frame(), 1);
        EXPECT_NE(e.reason().find("8x8"), std::string::npos) << e.reason();
        EXPECT_NE(e.reason().find("8x6"), std::string::npos) << e.reason();
    }
    ASSERT_TRUE(source.next(frame));  // the next call moves on
    EXPECT_EQ(frame.index, 2);
    EXPECT_EQ(uniformId(frame), 3);
    EXPECT_EQ(source.labelErrors(), 1);
}

TEST(LabelledImageSource, ColorCodedLabelImageIsRejected) {
    ScratchDir dir;
    const std::string color = dir.file("0.png");
    ASSERT_TRUE(cv::imwrite(color, cv::Mat(6, 8, CV_8UC3, cv::Scalar(10, 20, 30))));
    LabelledImageSource source(FakeSource::sequence(1), optionsFor(dir.path()));
    RGBDFrame frame;
    try {
        source.next(frame);
        ADD_FAILURE() << "no IoError for a 3-channel label image";
    } catch (const IoError& e) {
        EXPECT_EQ(e.file(), color);
        EXPECT_EQ(e.frame(), 0);
        EXPECT_NE(e.reason().find("this one has 3 channels"), std::string::npos) << e.reason();
    }
}

TEST(LabelledImageSource, FloatLabelImageIsRejected) {
    ScratchDir dir;
    const std::string path = dir.file("float.tif");
    ASSERT_TRUE(cv::imwrite(path, cv::Mat(6, 8, CV_32FC1, cv::Scalar(2.0))));
    try {
        readLabelImage(path, 0);
        ADD_FAILURE() << "no IoError for a float label image";
    } catch (const IoError& e) {
        EXPECT_EQ(e.file(), path);
        EXPECT_NE(e.reason().find("32-bit float"), std::string::npos) << e.reason();
    }
}

TEST(LabelledImageSource, CorruptLabelFileThrowsThenTheNextFrameWorks) {
    ScratchDir dir;
    writeLabels(dir.file("0.png"), 1);
    writeBytes(dir.file("1.png"), "\x89PNG\r\n\x1a\n truncated");
    writeLabels(dir.file("2.png"), 3);
    LabelledImageSource source(FakeSource::sequence(3), optionsFor(dir.path()));
    RGBDFrame frame;
    ASSERT_TRUE(source.next(frame));
    EXPECT_EQ(uniformId(frame), 1);
    try {
        source.next(frame);
        ADD_FAILURE() << "no IoError for a corrupt label file";
    } catch (const IoError& e) {
        EXPECT_EQ(e.file(), dir.file("1.png"));
        EXPECT_EQ(e.frame(), 1);
        EXPECT_NE(e.reason().find("cannot decode image"), std::string::npos) << e.reason();
        EXPECT_NE(std::string(e.what()).find("frame 1"), std::string::npos) << e.what();
    }
    ASSERT_TRUE(source.next(frame));
    EXPECT_EQ(frame.index, 2);
    EXPECT_EQ(uniformId(frame), 3);
    EXPECT_FALSE(source.next(frame));
    EXPECT_EQ(source.framesWithLabels(), 2);
    EXPECT_EQ(source.labelErrors(), 1);
}

TEST(LabelledImageSource, ConstructionErrors) {
    ScratchDir dir;
    const std::string empty = dir.file("empty/");
    std::filesystem::create_directories(empty);
    expectConstructionIoError([&] { LabelledImageSource s(FakeSource::sequence(1), optionsFor(empty)); }, empty,
                              "no label images");

    const std::string jpegs = dir.file("jpegs");
    std::filesystem::create_directories(jpegs);
    ASSERT_TRUE(cv::imwrite(jpegs + "/0.jpg", cv::Mat(6, 8, CV_8UC1, cv::Scalar(1))));
    expectConstructionIoError([&] { LabelledImageSource s(FakeSource::sequence(1), optionsFor(jpegs)); }, jpegs,
                              "JPEG");

    const std::string missing = dir.file("nowhere");
    expectConstructionIoError([&] { LabelledImageSource s(FakeSource::sequence(1), optionsFor(missing)); }, missing,
                              "no such label folder or list file");

    const std::string empty_list = dir.file("empty.txt");
    writeBytes(empty_list, "# nothing\n");
    expectConstructionIoError([&] { LabelledImageSource s(FakeSource::sequence(1), optionsFor(empty_list)); },
                              empty_list, "names no images");

    const std::string single = dir.file("one.png");
    writeLabels(single, 1);
    expectConstructionIoError([&] { LabelledImageSource s(FakeSource::sequence(1), optionsFor(single)); }, single,
                              "this is an image");

    EXPECT_THROW(LabelledImageSource(FakeSource::sequence(1), optionsFor("")), ConfigError);
    EXPECT_THROW(LabelledImageSource(nullptr, optionsFor(dir.path())), ConfigError);
    LabelStreamOptions bad_tolerance = optionsFor(dir.path());
    bad_tolerance.max_time_difference_s = -1.0;
    EXPECT_THROW(LabelledImageSource(FakeSource::sequence(1), bad_tolerance), ConfigError);
    LabelStreamOptions bad_ignore = optionsFor(dir.path());
    bad_ignore.ignore_id = 70000;
    EXPECT_THROW(LabelledImageSource(FakeSource::sequence(1), bad_ignore), ConfigError);
}

TEST(LabelledImageSource, ForwardsTheSourceAndDescribesTheLabels) {
    ScratchDir dir;
    writeLabels(dir.file("0.png"), 1);
    writeLabels(dir.file("1.png"), 2);
    auto inner = FakeSource::sequence(5);
    const RGBDCalib* inner_calib = &inner->calib();
    LabelledImageSource source(std::move(inner), optionsFor(dir.path()));
    EXPECT_EQ(&source.calib(), inner_calib);
    EXPECT_EQ(source.frameCount(), 5);
    EXPECT_TRUE(source.isLive());
    EXPECT_EQ(source.groundTruth().size(), 1u);
    const std::string d = source.description();
    EXPECT_EQ(d.rfind("fake source + labels from " + dir.path(), 0), 0u) << d;
    EXPECT_NE(d.find("2 label images, matched by frame index"), std::string::npos) << d;
    EXPECT_NE(d.find("class 0 = no label"), std::string::npos) << d;
}

}  // namespace
}  // namespace voxfuse
