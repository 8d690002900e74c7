#include "EngineOptions.h"

#include <algorithm>
#include <iostream>

#include "OptionChecks.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/engines/TrackerSettings.h"

namespace voxfuse::app {

bool EngineOptions::wasGiven(const char* option) const {
    return std::find(given.begin(), given.end(), option) != given.end();
}

namespace {

// The row's range or choices as a CLI11 check of each value given.
CLI::Validator rowCheck(const SettingRow& row, bool is_float) {
    if (is_float) return floatIn(row.min, row.max, row.min_open);
    return intIn((long long)row.min, (long long)row.max);
}

// "{hash,dense}", as CLI11 writes its own choices.
std::string choicesList(const SettingRow& row) {
    if (!*row.choices) return "TEXT";
    std::string list = row.choices;
    std::replace(list.begin(), list.end(), ' ', ',');
    return "{" + list + "}";
}

CLI::Validator textCheck(const SettingRow& row) {
    return CLI::Validator(
        [&row](std::string& value) -> std::string {
            PipelineSettings probe;
            probe.*std::get<std::string PipelineSettings::*>(row.member) = value;
            return settingProblem(row, probe);
        },
        choicesList(row));
}

CLI::Option* addOne(CLI::App& cli, const SettingRow& row, PipelineSettings& s) {
    const std::string name = optionName(row), help = settingDescription(row);
    return std::visit(
        [&](auto member) -> CLI::Option* {
            auto& value = s.*member;
            using T = std::decay_t<decltype(value)>;
            if constexpr (std::is_same_v<T, bool>) {
                if (row.cli == CliForm::Flag) return cli.add_flag(name, value, help);
                return cli
                    .add_option_function<std::string>(
                        name, [&value](const std::string& mode) { value = mode == "on"; }, help)
                    ->default_str(value ? "on" : "off")
                    ->check(CLI::IsMember({"on", "off"}));
            } else if constexpr (std::is_same_v<T, std::string>) {
                CLI::Option* o = cli.add_option(name, value, help)->check(textCheck(row));
                return value.empty() ? o : o->capture_default_str();
            } else if constexpr (std::is_same_v<T, int> || std::is_same_v<T, float>) {
                return cli.add_option(name, value, help)
                    ->capture_default_str()
                    ->check(rowCheck(row, std::is_same_v<T, float>));
            } else {
                constexpr bool is_float = std::is_same_v<typename T::value_type, float>;
                CLI::Option* o = cli.add_option(name, value, help)->check(rowCheck(row, is_float));
                if (row.list_size > 0) o->expected(row.list_size);
                return value.empty() ? o : o->capture_default_str();
            }
        },
        row.member);
}

// A former spelling: hidden, the same value and checks, a warning naming the current option.
void addFormerOption(CLI::App& cli, const SettingRow& row, CLI::Option* current, PipelineSettings& s) {
    std::string former = std::string("--") + row.former_name;
    std::replace(former.begin(), former.end(), '_', '-');
    std::visit(
        [&](auto member) {
            using T = std::decay_t<decltype(s.*member)>;
            if constexpr (std::is_same_v<T, int> || std::is_same_v<T, float>)
                addFormerSpelling(cli, former, current, s.*member)->check(rowCheck(row, std::is_same_v<T, float>));
            else
                throw Error(std::string("setting ") + row.name + ": former spellings are for numbers only");
        },
        row.member);
}

}  // namespace

void addSettingOptions(CLI::App& cli, PipelineSettings& s, SettingGroup group) {
    for (const SettingRow& row : pipelineSettingRows()) {
        if (row.group != group) continue;
        CLI::Option* option = addOne(cli, row, s);
        if (*row.former_name) addFormerOption(cli, row, option, s);
    }
}

void addMapOptions(CLI::App& cli, EngineOptions& o) {
    addSettingOptions(cli, o.settings, SettingGroup::Map);
    // On the command line --active-blocks always means swapping (0: as many blocks as --max-blocks).
    cli.get_option("--active-blocks")->each([&o](const std::string&) { o.settings.swap = true; });
}

void addTrackingOptions(CLI::App& cli, EngineOptions& o) {
    cli.add_option("--poses", o.poses, "track the camera, or take the source's ground truth")
        ->capture_default_str()
        ->check(CLI::IsMember({"track", "groundtruth"}));
    addSettingOptions(cli, o.settings, SettingGroup::Tracking);
    cli.add_flag_callback(
        "--tracker-keys",
        [] {
            std::cout << trackerSettingKeys();
            throw CLI::Success();
        },
        "print every key a --tracker-config file may set, with its default and meaning (as a settings file), and "
        "exit");
}

void noteGivenOptions(const CLI::App& cli, EngineOptions& o) {
    for (const CLI::Option* option : cli.get_options())
        if (option->count() > 0) o.given.push_back(option->get_name());  // "--index", or "source" for the positional
}

void checkEngineOptions(const EngineOptions& o, bool index_from_map) {
    auto refuse = [](const std::string& why) { throw ConfigError(why); };
    const PipelineSettings& s = o.settings;
    const bool dense = s.index == "dense";
    for (const char* option : {"--volume-size", "--volume-offset"})
        if (o.wasGiven(option) && !dense && !index_from_map)
            refuse(std::string(option) + " sets the dense volume: it needs --index dense");
    for (const char* option : {"--max-blocks", "--hash-buckets", "--hash-excess"})
        if (o.wasGiven(option) && dense)
            refuse(std::string(option) + " sets the hash index: it does nothing with --index dense");
    const bool swapping = s.swap || s.active_blocks > 0 || !s.swap_file.empty();
    if (o.wasGiven("--swap-blocks-per-frame") && !swapping)
        refuse("--swap-blocks-per-frame needs swapping (--swap, --active-blocks or --swap-file)");
    if (swapping && dense) refuse("swapping needs the hash index (--index hash)");
    if (o.poses == "groundtruth")
        for (const char* option :
             {"--tracker", "--tracker-config", "--tracker-levels", "--tracker-iterations", "--tracker-max-distance"})
            if (o.wasGiven(option))
                refuse(std::string(option) + " sets the tracker, which --poses groundtruth does not use");
}

}  // namespace voxfuse::app
