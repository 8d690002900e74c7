// The tracker settings file: every key reaches its field, and bad lines are reported with file and line.

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <variant>
#include <cmath>

#include "voxfuse/core/Error.h"
#include "voxfuse/engines/Tracker.h"

namespace voxfuse {
namespace {

TEST(TrackerSettingsTest, DefaultsAreValidAndDocumented) {
    const TrackerSettings s;
    EXPECT_NO_THROW(validateTrackerSettings(s));
    EXPECT_EQ(s.levels.size(), 3u);
    EXPECT_EQ(s.levels.back().motion, LevelMotion::Both);
    EXPECT_TRUE(s.color_weight_auto);
    EXPECT_EQ(s.far_field_keyframes, 3) << "rgbd aligns to the far field too";
}

// --tracker-keys prints a settings file of the defaults: it names every key and reads back as the defaults.
TEST(TrackerSettingsTest, TheKeyListIsASettingsFileOfTheDefaults) {
    const std::string keys = trackerSettingKeys();
    for (const TrackerSettingRow& row : trackerSettingRows())
        EXPECT_NE(keys.find(std::string("\n") + row.key + " = "), std::string::npos) << row.key;
    const TrackerSettings parsed = parseTrackerSettings(keys, "keys"), defaults;
    for (const TrackerSettingRow& row : trackerSettingRows())
        std::visit([&](auto field) { EXPECT_EQ(parsed.*field, defaults.*field) << row.key; }, row.field);
    ASSERT_EQ(parsed.levels.size(), defaults.levels.size());
    for (std::size_t i = 0; i < parsed.levels.size(); ++i) {
        EXPECT_EQ(parsed.levels[i].pixel_step, defaults.levels[i].pixel_step);
        EXPECT_EQ(parsed.levels[i].max_distance_m, defaults.levels[i].max_distance_m);
    }
    EXPECT_EQ(parsed.color_weight_auto, defaults.color_weight_auto);
}

// Every numeric row's range is what the file accepts: its closed ends in, a step beyond either end out.
TEST(TrackerSettingsTest, EveryKeyIsCheckedAgainstItsRange) {
    for (const TrackerSettingRow& row : trackerSettingRows()) {
        const bool is_int = std::holds_alternative<int TrackerSettings::*>(row.field);
        if (!is_int && !std::holds_alternative<float TrackerSettings::*>(row.field)) continue;
        auto text = [&](double v) {
            std::ostringstream out;
            out.precision(9);
            out << (is_int ? double(std::llround(v)) : v);
            return out.str();
        };
        // The quality pairs must stay ordered (failed <= good): the other of a pair at its widest.
        std::string others;
        for (const auto& [key, value] : {std::pair{"good_inlier_ratio", "1"},
                                         {"failed_inlier_ratio", "0"},
                                         {"good_condition", "1"},
                                         {"failed_condition", "0"}})
            if (key != std::string(row.key)) others += std::string(key) + " = " + value + "\n";
        auto parses = [&](double v) {
            try {
                parseTrackerSettings(others + row.key + " = " + text(v) + "\n", "t.cfg");
                return true;
            } catch (const ParseError& e) {
                EXPECT_NE(std::string(e.what()).find(row.key), std::string::npos) << e.what();
                return false;
            }
        };
        const double step = is_int ? 1.0 : 1e-3;
        EXPECT_FALSE(parses(row.min - step)) << row.key;
        if (!row.min_open) EXPECT_TRUE(parses(row.min)) << row.key;
        if (std::isfinite(row.max) && row.max < 1e9) {
            EXPECT_FALSE(parses(row.max + step)) << row.key;
            if (!row.max_open) EXPECT_TRUE(parses(row.max)) << row.key;
        }
    }
}

TEST(TrackerSettingsTest, ParsesEveryKindOfValue) {
    const TrackerSettings s = parseTrackerSettings(
        "# comment line\n"
        "tracker = icp   # trailing comment (the default is rgbd)\n"
        "\n"
        "levels = rrtb\n"
        "iterations = 20 10 5 3\n"
        "max_distance_m = 0.2\n"
        "pixel_step = 1 1 2 4\n"
        "bilateral_filter = off\n"
        "extrapolate_steps = false\n"
        "robust_kernel = huber\n"
        "color_weight = 0.5\n"
        "color_from_map = false\n"
        "poor_translation_constraint = 0\n"
        "max_tracking_depth_m = 2.5\n"
        "far_field_keyframes = 0\n"
        "far_field_spacing_m = 0.1\n"
        "far_field_spacing_deg = 5\n"
        "far_field_point_share = 1\n"
        "min_inliers = 50\n",
        "test.txt");
    EXPECT_EQ(s.kind, TrackerKind::Icp);
    ASSERT_EQ(s.levels.size(), 4u);
    EXPECT_EQ(s.levels[0].motion, LevelMotion::Rotation);
    EXPECT_EQ(s.levels[2].motion, LevelMotion::Translation);
    EXPECT_EQ(s.levels[3].motion, LevelMotion::Both);
    EXPECT_EQ(s.levels[0].max_iterations, 20);
    EXPECT_EQ(s.levels[3].max_iterations, 3);
    for (const TrackerLevel& l : s.levels) EXPECT_FLOAT_EQ(l.max_distance_m, 0.2f);
    EXPECT_EQ(s.levels[0].pixel_step, 1);
    EXPECT_EQ(s.levels[2].pixel_step, 2);
    EXPECT_EQ(s.levels[3].pixel_step, 4);
    EXPECT_FALSE(s.bilateral_filter);
    EXPECT_FALSE(s.extrapolate_steps);
    EXPECT_EQ(s.robust_kernel, RobustKernel::Huber);
    EXPECT_FLOAT_EQ(s.color_weight, 0.5f);
    EXPECT_FALSE(s.color_weight_auto) << "a number fixes the colour weight";
    EXPECT_FALSE(s.color_from_map);
    EXPECT_EQ(s.poor_translation_constraint, 0.f);
    EXPECT_FLOAT_EQ(s.max_tracking_depth_m, 2.5f);
    EXPECT_EQ(s.far_field_keyframes, 0);
    EXPECT_FLOAT_EQ(s.far_field_spacing_m, 0.1f);
    EXPECT_FLOAT_EQ(s.far_field_spacing_deg, 5.f);
    EXPECT_FLOAT_EQ(s.far_field_point_share, 1.f);
    EXPECT_EQ(s.min_inliers, 50);
}

TEST(TrackerSettingsTest, ANewLevelStringKeepsTheFineLevelDefaults) {
    const TrackerSettings defaults;
    const TrackerSettings s = parseTrackerSettings("levels = rbbb\n", "x");
    ASSERT_EQ(s.levels.size(), 4u);
    EXPECT_FLOAT_EQ(s.levels[3].max_distance_m, defaults.levels[2].max_distance_m);
    EXPECT_EQ(s.levels[3].pixel_step, defaults.levels[2].pixel_step);
    EXPECT_FLOAT_EQ(s.levels[0].max_distance_m, defaults.levels[0].max_distance_m);
}

void expectParseError(const std::string& text, int line, const std::string& reason_part) {
    try {
        parseTrackerSettings(text, "bad.txt");
        FAIL() << "no error for: " << text;
    } catch (const ParseError& e) {
        EXPECT_EQ(e.file(), "bad.txt");
        EXPECT_EQ(e.line(), line) << e.what();
        EXPECT_NE(e.reason().find(reason_part), std::string::npos) << e.what();
    }
}

TEST(TrackerSettingsTest, BadLinesNameFileLineAndReason) {
    expectParseError("tracker = icp\nspeed = 3\n", 2, "unknown tracker setting 'speed'");
    expectParseError("tracker = fast\n", 1, "unknown tracker 'fast'");
    expectParseError("# x\nlevels = rxb\n", 2, "level types");
    expectParseError("levels = bb\niterations = 1 2 3\n", 2, "expected 1 or 2 values");
    expectParseError("iterations = 10 2.5 3\n", 1, "integers");
    expectParseError("max_distance_m = 0.1 -0.05 0.02\n", 1, "distance thresholds must be > 0");
    expectParseError("pixel_step = 1 0 1\n", 1, "pixel_step: expected integers in 1..8");
    expectParseError("pixel_step = 1.5\n", 1, "pixel_step: expected integers in 1..8");
    expectParseError("max_normal_angle_deg = abc\n", 1, "not a number");
    expectParseError("robust_scale_m = 1e39\n", 1, "in float range): '1e39'");  // infinite as a float
    expectParseError("max_distance_m = 0.1 1e39 0.02\n", 1, "in float range): '1e39'");
    expectParseError("bilateral_filter = maybe\n", 1, "true or false");
    expectParseError("just some words\n", 1, "key = value");
    expectParseError("color_weight =\n", 1, "no value");
    expectParseError("color_weight = automatic\n", 1, "expected auto or a number, got 'automatic'");
    expectParseError("good_inlier_ratio = 0.3\n\nfailed_inlier_ratio = 0.5\n", 3, "must not exceed");
    expectParseError("poor_translation_constraint = 0.34\n", 1, "must be in [0, 0.333333)");
    expectParseError("max_tracking_depth_m = -1\n", 1, "must be >= 0");
    expectParseError("far_field_keyframes = -1\n", 1, "must be in 0..16");
    expectParseError("far_field_spacing_m = -0.1\n", 1, "must be >= 0");
    expectParseError("far_field_point_share = 0\n", 1, "must be in (0, 1]");
    expectParseError("tracker = icp\n# later\ntracker = ren\n", 3, "'tracker' is set twice (first on line 1)");
}

TEST(TrackerSettingsTest, ColorWeightIsAutomaticOrANumber) {
    EXPECT_TRUE(parseTrackerSettings("color_weight = auto\n", "test.txt").color_weight_auto);
    const TrackerSettings fixed = parseTrackerSettings("color_weight = 2e-3\n", "test.txt");
    EXPECT_FALSE(fixed.color_weight_auto);
    EXPECT_FLOAT_EQ(fixed.color_weight, 2e-3f);
    EXPECT_THROW(parseTrackerSettings("color_weight = -1\n", "test.txt"), ParseError) << "a fixed weight is >= 0";
}

// A file's key may be overridden by a front-end's single value (the file said it once); the conflict
// of a file's per-level list with an overridden level string names the levels it was checked against.
TEST(TrackerSettingsTest, SingleValuesOverrideTheFileAndConflictsSayWithWhat) {
    const std::string path = (std::filesystem::temp_directory_path() / "voxfuse_tracker_overrides_test.txt").string();
    {
        std::ofstream out(path);
        out << "tracker = icp\niterations = 5 5 5\n";
    }
    TrackerOverrides o;
    o.settings_file = path;
    o.kind = "ren";
    o.origin = "the --tracker options";
    EXPECT_EQ(trackerSettingsWith(o).kind, TrackerKind::Ren);
    o.levels = "bb";
    try {
        trackerSettingsWith(o);
        FAIL() << "three iteration counts for two levels were accepted";
    } catch (const ParseError& e) {
        EXPECT_NE(
            std::string(e.what()).find("iterations: expected 1 or 2 values (one per level of levels = bb), got 3"),
            std::string::npos)
            << e.what();
    }
    std::remove(path.c_str());
}

TEST(TrackerSettingsTest, ReadsAFileAndReportsAMissingOne) {
    const std::string path = (std::filesystem::temp_directory_path() / "voxfuse_tracker_settings_test.txt").string();
    {
        std::ofstream out(path);
        out << "tracker = icp\nlevels = bbb\niterations = 8 6 4\n";
    }
    const TrackerSettings s = parseTrackerSettingsFile(path);
    EXPECT_EQ(s.kind, TrackerKind::Icp);
    EXPECT_EQ(s.levels[1].max_iterations, 6);
    std::remove(path.c_str());
    EXPECT_THROW(parseTrackerSettingsFile(path), IoError);
}

TEST(TrackerSettingsTest, SingleValuesAreNamedByTheirOriginAndAFolderIsNoFile) {
    TrackerOverrides o;
    o.levels = "rbb";
    o.iterations = {5, 5};  // three levels
    o.origin = "the --tracker options";
    try {
        trackerSettingsWith(o);
        FAIL() << "two iteration counts for three levels were accepted";
    } catch (const ParseError& e) {
        FAIL() << "a line number for values that came from no file: " << e.what();
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("the --tracker options: iterations: expected 1 or 3 values"),
                  std::string::npos)
            << e.what();
    }
    const std::string folder = std::filesystem::temp_directory_path().string();
    try {
        parseTrackerSettingsFile(folder);
        FAIL() << "a folder was read as a settings file";
    } catch (const IoError& e) {
        EXPECT_NE(e.reason().find("is a folder, not a file"), std::string::npos) << e.what();
    }
}

TEST(TrackerSettingsTest, MakeTrackerRejectsInvalidSettings) {
    TrackerSettings s;
    s.levels.clear();
    EXPECT_THROW(makeTracker(s, Device::CPU), ConfigError);
    s = TrackerSettings();
    s.min_inliers = 2;
    EXPECT_THROW(makeTracker(s, Device::CPU), ConfigError);
    EXPECT_THROW(parseTrackerKind("orb"), ConfigError);
    for (TrackerKind k : {TrackerKind::Icp, TrackerKind::Color, TrackerKind::Ren, TrackerKind::Rgbd})
        EXPECT_EQ(parseTrackerKind(toString(k)), k);
}

}  // namespace
}  // namespace voxfuse
