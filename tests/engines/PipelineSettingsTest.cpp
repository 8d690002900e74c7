// The settings table (engines/PipelineSettings.h): its defaults are the engine's, each row's check
// refuses what lies outside its range, and the engine's settings translate back to the same table.

#include <gtest/gtest.h>

#include <set>

#include "voxfuse/core/Error.h"
#include "voxfuse/engines/PipelineSettings.h"
#include "voxfuse/engines/TrackerSettings.h"

namespace voxfuse {
namespace {

TEST(PipelineSettingsTest, RowsHaveUniqueSnakeCaseNamesAndTheirDefaultsPassTheirChecks) {
    std::set<std::string> names;
    const PipelineSettings defaults;
    for (const SettingRow& row : pipelineSettingRows()) {
        const std::string name = row.name;
        EXPECT_TRUE(names.insert(name).second) << name << " twice";
        EXPECT_EQ(name.find_first_not_of("abcdefghijklmnopqrstuvwxyz_"), std::string::npos) << name;
        EXPECT_FALSE(std::string(row.help).empty()) << name << " has no help";
        EXPECT_EQ(settingProblem(row, defaults), "") << name;
        EXPECT_EQ(findSettingRow(name), &row);
    }
    EXPECT_EQ(findSettingRow("voxelsize"), nullptr);
    EXPECT_EQ(optionName(*findSettingRow("relocalise_min_color_correlation")), "--relocalise-min-color-correlation");
}

// The table's defaults make the engine's own: a default changed in one place and not the other fails here.
TEST(PipelineSettingsTest, DefaultsAreTheEngines) {
    const MainEngineSettings made = PipelineSettings{}.toEngineSettings(), engine;
    EXPECT_EQ(made.voxel_type, engine.voxel_type);
    EXPECT_EQ(made.index_type, engine.index_type);
    EXPECT_EQ(made.device, engine.device);
    EXPECT_EQ(made.scene.voxel_size_m, engine.scene.voxel_size_m);
    EXPECT_EQ(made.scene.mu_m, engine.scene.mu_m);
    EXPECT_EQ(made.scene.max_weight, engine.scene.max_weight);
    EXPECT_EQ(made.scene.view_frustum_min_m, engine.scene.view_frustum_min_m);
    EXPECT_EQ(made.scene.view_frustum_max_m, engine.scene.view_frustum_max_m);
    EXPECT_EQ(made.scene.label_update, engine.scene.label_update);
    EXPECT_EQ(made.depth_gap_tolerance, engine.depth_gap_tolerance);
    EXPECT_EQ(made.hash.max_block_count, engine.hash.max_block_count);
    EXPECT_EQ(made.hash.bucket_count, engine.hash.bucket_count);
    EXPECT_EQ(made.hash.excess_entry_count, engine.hash.excess_entry_count);
    for (int a = 0; a < 3; ++a) {
        EXPECT_EQ(made.dense_size[a], engine.dense_size[a]);
        EXPECT_EQ(made.dense_offset[a], engine.dense_offset[a]);
    }
    EXPECT_EQ(made.swap.enabled, engine.swap.enabled);
    EXPECT_EQ(made.swap.blocks_per_frame, engine.swap.blocks_per_frame);
    EXPECT_EQ(made.tracker.kind, engine.tracker.kind);
    ASSERT_EQ(made.tracker.levels.size(), engine.tracker.levels.size());
    for (std::size_t i = 0; i < made.tracker.levels.size(); ++i) {
        EXPECT_EQ(made.tracker.levels[i].motion, engine.tracker.levels[i].motion);
        EXPECT_EQ(made.tracker.levels[i].max_iterations, engine.tracker.levels[i].max_iterations);
        EXPECT_EQ(made.tracker.levels[i].max_distance_m, engine.tracker.levels[i].max_distance_m);
    }
    EXPECT_EQ(made.relocalisation.enabled, engine.relocalisation.enabled);
    EXPECT_EQ(made.relocalisation.candidates, engine.relocalisation.candidates);
    EXPECT_EQ(made.relocalisation.max_speed_m_per_s, engine.relocalisation.max_speed_m_per_s);
    EXPECT_EQ(made.relocalisation.min_color_correlation, engine.relocalisation.min_color_correlation);
}

TEST(PipelineSettingsTest, ValuesOutsideARowsRangeAreRefusedByName) {
    PipelineSettings s;
    s.voxel_size = 0.f;  // the range is (0, 1]
    EXPECT_NE(settingProblem(*findSettingRow("voxel_size"), s), "");
    try {
        (void)s.toEngineSettings();
        FAIL() << "voxel_size 0 was accepted";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("voxel_size: 0 is not in (0, 1]"), std::string::npos) << e.what();
    }
    s = PipelineSettings{};
    s.voxel_size = 1.f;  // the range's closed end
    EXPECT_EQ(settingProblem(*findSettingRow("voxel_size"), s), "");
    s.max_weight = 256;
    EXPECT_NE(settingProblem(*findSettingRow("max_weight"), s), "");
    s = PipelineSettings{};
    s.relocalise_max_speed = std::nanf("");
    EXPECT_NE(settingProblem(*findSettingRow("relocalise_max_speed"), s), "") << "NaN is in no range";
    s = PipelineSettings{};
    s.volume_size = {512, 512};
    EXPECT_EQ(settingProblem(*findSettingRow("volume_size"), s), "takes 3 numbers, not 2");
    s.volume_size = {512, 0, 512};
    EXPECT_EQ(settingProblem(*findSettingRow("volume_size"), s), "0 is not in [1, 65536]");
    s = PipelineSettings{};
    s.index = "octree";
    EXPECT_EQ(settingProblem(*findSettingRow("index"), s), "'octree' is not one of hash, dense");
    s = PipelineSettings{};
    s.tracker_levels = "rbx";
    EXPECT_NE(settingProblem(*findSettingRow("tracker_levels"), s), "");
    s.tracker_levels = "";  // the default: not given
    EXPECT_EQ(settingProblem(*findSettingRow("tracker_levels"), s), "");
    s.tracker_config = "/nowhere/tracker.cfg";
    EXPECT_NE(settingProblem(*findSettingRow("tracker_config"), s), "");
}

// of() is toEngineSettings' inverse: changed settings survive the way there and back.
TEST(PipelineSettingsTest, EngineSettingsTranslateBackToTheTable) {
    PipelineSettings s;
    s.voxel = "f";
    s.index = "dense";
    s.voxel_size = 0.01f;
    s.max_depth = 4.5f;
    s.volume_size = {128, 64, 32};
    s.volume_offset = {-64, -32, 0};
    s.label_update = "vote";
    s.tracker = "icp";
    s.tracker_levels = "rtbb";
    s.tracker_iterations = {4, 5, 6, 7};
    s.tracker_max_distance = {0.2f, 0.1f, 0.05f, 0.01f};
    s.relocalise = false;
    s.relocalise_candidates = 7;
    const PipelineSettings back = PipelineSettings::of(s.toEngineSettings());
    for (const SettingRow& row : pipelineSettingRows())
        EXPECT_EQ(settingText(row, back), settingText(row, s)) << row.name;

    PipelineSettings swapping;
    swapping.active_blocks = 5000;
    const MainEngineSettings e = swapping.toEngineSettings();
    EXPECT_TRUE(e.swap.enabled) << "active_blocks > 0 implies swap";
    EXPECT_EQ(e.hash.max_block_count, 5000);
    EXPECT_EQ(PipelineSettings::of(e).active_blocks, 5000);
}

TEST(PipelineSettingsTest, TextIsHowTheCommandLineWritesIt) {
    const PipelineSettings s;
    EXPECT_EQ(settingText(*findSettingRow("voxel_size"), s), "0.005");
    EXPECT_EQ(settingText(*findSettingRow("volume_size"), s), "512 512 512");
    EXPECT_EQ(settingText(*findSettingRow("relocalise"), s), "on");
    EXPECT_EQ(settingText(*findSettingRow("swap"), s), "false");
    EXPECT_EQ(floatAsDecimal(0.005f), 0.005);
}

}  // namespace
}  // namespace voxfuse
