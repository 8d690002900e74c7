// The command line's settings (apps/common/EngineOptions.h) are the table's: every row is an option
// with the row's default, and the option's check accepts and refuses what the row's check does.

#include <gtest/gtest.h>

#include <cmath>
#include <variant>

#include "EngineOptions.h"

namespace voxfuse::app {
namespace {

struct Cli {
    CLI::App app{"test"};
    EngineOptions options;
    Cli() {
        addMapOptions(app, options);
        addTrackingOptions(app, options);
    }
    // True when the command line takes `--option value`.
    bool takes(const std::string& option, const std::string& value) {
        Cli fresh;
        std::vector<std::string> args = {value, option};  // CLI11 parses a reversed argument list
        try {
            fresh.app.parse(args);
            return true;
        } catch (const CLI::ParseError&) {
            return false;
        }
    }
};

TEST(SettingOptionsTest, EveryRowIsAnOptionWithItsDefault) {
    Cli cli;
    const PipelineSettings defaults;
    for (const SettingRow& row : pipelineSettingRows()) {
        const CLI::Option* option = cli.app.get_option_no_throw(optionName(row));
        ASSERT_NE(option, nullptr) << optionName(row) << " is missing";
        EXPECT_NE(option->get_description().find(row.help), std::string::npos) << row.name;
        const std::string text = settingText(row, defaults);
        if (row.cli == CliForm::Flag || text.empty()) continue;
        std::string shown = option->get_default_str();
        for (const char* strip : {"[", "]"})
            for (std::size_t at; (at = shown.find(strip)) != std::string::npos;) shown.erase(at, 1);
        for (char& c : shown)
            if (c == ',') c = ' ';
        // CLI11 writes floats as the stream does: compare as numbers where the row is a number.
        if (row.max > row.min && text.find(' ') == std::string::npos)
            EXPECT_FLOAT_EQ(std::stof(shown), std::stof(text)) << row.name;
        else
            EXPECT_EQ(shown, text) << row.name;
    }
}

TEST(SettingOptionsTest, OptionsCheckWhatTheirRowsCheck) {
    Cli cli;
    for (const SettingRow& row : pipelineSettingRows()) {
        if (row.cli != CliForm::Value || !(row.max > row.min)) continue;
        const std::string option = optionName(row);
        if (row.list_size > 1) continue;  // three values: covered in ParsedOptionsReachTheSettings
        const bool is_float = std::holds_alternative<float PipelineSettings::*>(row.member) ||
                              std::holds_alternative<std::vector<float> PipelineSettings::*>(row.member);
        auto text = [&](double v) { return is_float ? std::to_string(v) : std::to_string((long long)v); };
        const std::string inside = text(row.max), beyond = text(row.max + (is_float ? row.max * 0.01 + 0.01 : 1.0));
        const std::string below = text(row.min_open ? row.min : row.min - 1.0);
        EXPECT_TRUE(cli.takes(option, inside)) << option << " " << inside;
        EXPECT_FALSE(cli.takes(option, beyond)) << option << " " << beyond;
        EXPECT_FALSE(cli.takes(option, below)) << option << " " << below;
        EXPECT_FALSE(cli.takes(option, "nan")) << option;
    }
    EXPECT_FALSE(cli.takes("--index", "octree"));
    EXPECT_TRUE(cli.takes("--tracker-levels", "rbb"));
    EXPECT_FALSE(cli.takes("--tracker-levels", "rbx"));
    EXPECT_FALSE(cli.takes("--tracker-config", "/nowhere/tracker.cfg"));
}

TEST(SettingOptionsTest, ParsedOptionsReachTheSettings) {
    Cli cli;
    const std::vector<std::string> args = {
        "--label-update", "vote", "--relocalise", "off", "--voxel-size", "0.01", "--volume-offset", "0", "1", "2"};
    cli.app.parse(std::vector<std::string>(args.rbegin(), args.rend()));  // CLI11 takes them reversed
    EXPECT_EQ(cli.options.settings.label_update, "vote");
    EXPECT_FALSE(cli.options.settings.relocalise);
    EXPECT_FLOAT_EQ(cli.options.settings.voxel_size, 0.01f);
    EXPECT_EQ(cli.options.settings.volume_offset, (std::vector<int>{0, 1, 2}));
    Cli swapping;
    swapping.app.parse(std::vector<std::string>{"0", "--active-blocks"});
    EXPECT_TRUE(swapping.options.settings.swap) << "--active-blocks means swapping, also with 0";
}

}  // namespace
}  // namespace voxfuse::app
