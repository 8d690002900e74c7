// Tracker settings: names, validation and the "key = value" settings file.

#include "voxfuse/engines/TrackerSettings.h"

#include <algorithm>
#include <charconv>
#include <climits>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <sstream>

#include "../io/TextParsing.h"
#include "voxfuse/core/Error.h"

namespace voxfuse {
namespace {

std::string trim(const std::string& s) {
    const auto first = s.find_first_not_of(" \t\r");
    if (first == std::string::npos) return {};
    return s.substr(first, s.find_last_not_of(" \t\r") - first + 1);
}

std::string formatNumber(double v) {
    std::ostringstream out;
    out << v;
    return out.str();
}

using T = TrackerSettings;
constexpr double kNoLimit = std::numeric_limits<double>::infinity();

// key, field, min, max, min_open, max_open, help
const std::vector<TrackerSettingRow> kRows = {
    {"max_normal_angle_deg", &T::max_normal_angle_deg, 0, 180, true, false,
     "frame and model normals further apart reject the pair (degrees; 180: no test)"},
    {"min_rotation_step_rad", &T::min_rotation_step_rad, 0, kNoLimit, false, false,
     "a level stops iterating once an update rotates less than this and translates less than "
     "min_translation_step_m (coarser levels: 2^k times both)"},
    {"min_translation_step_m", &T::min_translation_step_m, 0, kNoLimit, false, false,
     "see min_rotation_step_rad (metres)"},
    {"bilateral_filter", &T::bilateral_filter, 0, 0, false, false,
     "edge-preserving smoothing of the depth before the pyramid is built"},
    {"predict_motion", &T::predict_motion, 0, 0, false, false,
     "start from the pose the last two frames' motion predicts, not the last pose"},
    {"extrapolate_steps", &T::extrapolate_steps, 0, 0, false, false,
     "stretch a Gauss-Newton step that continues the one before it"},
    {"max_normal_edge_m", &T::max_normal_edge_m, 0, kNoLimit, true, false,
     "frame normals only between neighbours closer than this (metres at full resolution; larger gaps are edges)"},
    {"max_tracking_depth_m", &T::max_tracking_depth_m, 0, kNoLimit, false, false,
     "frame depths beyond this take no part in depth tracking but are fused (metres; 0: no limit)"},
    {"robust_kernel", &T::robust_kernel, 0, 0, false, false, "ren and rgbd: the robust cost of the depth terms"},
    {"robust_scale_m", &T::robust_scale_m, 0, kNoLimit, true, false,
     "its scale: Tukey gives residuals beyond this no weight (metres)"},
    {"color_point_step", &T::color_point_step, 1, 16, false, false,
     "color and rgbd: model points every this many pixels in x and y"},
    {"color_kernel", &T::color_kernel, 0, 0, false, false, "the robust cost of the photometric terms"},
    {"color_kernel_scale", &T::color_kernel_scale, 0, kNoLimit, true, false, "its scale (intensities are in [0, 1])"},
    {"color_from_map", &T::color_from_map, 0, 0, false, false,
     "rgbd: align to the map's fused colours (false: the previous frame's)"},
    {"far_field_keyframes", &T::far_field_keyframes, 0, 16, false, false,
     "rgbd: keyframes of the depths beyond the map whose points join the photometric terms (0: off)"},
    {"far_field_spacing_m", &T::far_field_spacing_m, 0, kNoLimit, false, false,
     "camera motion between two far-field keyframes (metres)"},
    {"far_field_spacing_deg", &T::far_field_spacing_deg, 0, kNoLimit, false, false, "or turn between them (degrees)"},
    {"far_field_point_share", &T::far_field_point_share, 0, 1, true, false,
     "share of a keyframe's points kept, where its image is most textured"},
    {"good_inlier_ratio", &T::good_inlier_ratio, 0, 1, false, false, "inlier ratio below this: poor"},
    {"failed_inlier_ratio", &T::failed_inlier_ratio, 0, 1, false, false, "inlier ratio below this: failed"},
    {"good_condition", &T::good_condition, 0, 1, false, false,
     "smallest / largest eigenvalue of the scaled normal matrix below this: poor"},
    {"failed_condition", &T::failed_condition, 0, 1, false, false, "below this: failed"},
    // Above 1/3 even normals pointing evenly everywhere would be poor.
    {"poor_translation_constraint", &T::poor_translation_constraint, 0, 1.0 / 3.0, false, true,
     "share of the depth terms' weight along the least constrained translation below this: poor"},
    {"poor_residual_m", &T::poor_residual_m, 0, kNoLimit, true, false,
     "RMS point-to-plane residual above this: poor (metres)"},
    {"failed_color_residual", &T::failed_color_residual, 0, kNoLimit, true, false,
     "color tracker: RMS intensity error above this: failed"},
    {"min_inliers", &T::min_inliers, 6, INT_MAX, false, false,
     "fewer full-resolution inliers: failed (a pose has 6 parameters)"},
    {"max_motion_m", &T::max_motion_m, 0, kNoLimit, true, false,
     "a frame-to-frame motion beyond this is not believed: failed (metres)"},
    {"max_motion_deg", &T::max_motion_deg, 0, 180, true, false, "a turn beyond this is not believed: failed (degrees)"},
};

// "must be in (0, 180]", "must be > 0", "must be in 0..16": the row's range, "" when `v` is in it.
std::string rangeProblem(const TrackerSettingRow& row, double v, bool is_int) {
    const bool in =
        std::isfinite(v) && (row.min_open ? v > row.min : v >= row.min) && (row.max_open ? v < row.max : v <= row.max);
    if (in) return {};
    if (is_int)
        return row.max >= INT_MAX ? "must be >= " + formatNumber(row.min)
                                  : "must be in " + formatNumber(row.min) + ".." + formatNumber(row.max);
    if (std::isinf(row.max)) return std::string("must be ") + (row.min_open ? "> " : ">= ") + formatNumber(row.min);
    return std::string("must be in ") + (row.min_open ? "(" : "[") + formatNumber(row.min) + ", " +
           formatNumber(row.max) + (row.max_open ? ")" : "]");
}

std::string rowProblem(const TrackerSettingRow& row, const TrackerSettings& s) {
    return std::visit(
        [&](auto field) -> std::string {
            using V = std::decay_t<decltype(s.*field)>;
            if constexpr (std::is_same_v<V, float> || std::is_same_v<V, int>)
                return rangeProblem(row, double(s.*field), std::is_same_v<V, int>);
            return {};
        },
        row.field);
}

// The first setting out of range: the keys involved (settings-file names) and why; false when all are fine.
bool findInvalidSetting(const TrackerSettings& s, std::vector<std::string>& keys, std::string& reason) {
    auto fail = [&](std::vector<std::string> k, std::string r) {
        keys = std::move(k);
        reason = std::move(r);
        return true;
    };
    if (s.levels.empty() || s.levels.size() > 8) return fail({"levels"}, "need 1 to 8 pyramid levels");
    for (const TrackerLevel& l : s.levels) {
        if (l.motion != LevelMotion::Rotation && l.motion != LevelMotion::Translation && l.motion != LevelMotion::Both)
            return fail({"levels"}, "level types are r, t or b");
        if (l.max_iterations < 1 || l.max_iterations > 1000)
            return fail({"iterations"}, "iterations must be in 1..1000");
        if (!(l.max_distance_m > 0.f && std::isfinite(l.max_distance_m)))
            return fail({"max_distance_m"}, "distance thresholds must be > 0");
        if (l.pixel_step < 1 || l.pixel_step > 8) return fail({"pixel_step"}, "pixel steps must be in 1..8");
    }
    for (const TrackerSettingRow& row : kRows)
        if (std::string why = rowProblem(row, s); !why.empty()) return fail({row.key}, why);
    if (!(s.color_weight >= 0.f && std::isfinite(s.color_weight))) return fail({"color_weight"}, "must be >= 0");
    if (s.failed_inlier_ratio > s.good_inlier_ratio)
        return fail({"failed_inlier_ratio", "good_inlier_ratio"},
                    "failed_inlier_ratio must not exceed good_inlier_ratio");
    if (s.failed_condition > s.good_condition)
        return fail({"failed_condition", "good_condition"}, "failed_condition must not exceed good_condition");
    return false;
}

RobustKernel parseKernel(const std::string& v, bool& ok) {
    ok = true;
    if (v == "none") return RobustKernel::None;
    if (v == "huber") return RobustKernel::Huber;
    if (v == "tukey") return RobustKernel::Tukey;
    ok = false;
    return RobustKernel::None;
}

// Levels for a new level string: per-level defaults aligned at the fine end (the coarsest default
// repeats for extra coarse levels).
std::vector<TrackerLevel> levelsFor(const std::string& types) {
    const std::vector<TrackerLevel> defaults = TrackerSettings().levels;
    const int n = int(types.size()), d = int(defaults.size());
    std::vector<TrackerLevel> levels(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
        const int from_fine = n - 1 - i;
        levels[std::size_t(i)] = defaults[std::size_t(std::max(0, d - 1 - from_fine))];
        levels[std::size_t(i)].motion = LevelMotion(types[std::size_t(i)]);
    }
    return levels;
}

}  // namespace

const char* toString(TrackerKind kind) {
    switch (kind) {
        case TrackerKind::Icp:
            return "icp";
        case TrackerKind::Color:
            return "color";
        case TrackerKind::Ren:
            return "ren";
        case TrackerKind::Rgbd:
            return "rgbd";
    }
    return "?";
}

TrackerKind parseTrackerKind(const std::string& name) {
    if (name == "icp") return TrackerKind::Icp;
    if (name == "color") return TrackerKind::Color;
    if (name == "ren") return TrackerKind::Ren;
    if (name == "rgbd") return TrackerKind::Rgbd;
    throw ConfigError("unknown tracker '" + name + "' (expected icp, color, ren or rgbd)");
}

const std::vector<TrackerSettingRow>& trackerSettingRows() { return kRows; }

namespace {

const char* kernelName(RobustKernel k) {
    return k == RobustKernel::None ? "none" : k == RobustKernel::Huber ? "huber" : "tukey";
}

// The shortest text that reads back as `v`.
std::string floatText(float v) {
    char text[32];
    return std::string(text, std::to_chars(text, text + sizeof text, v).ptr);
}

}  // namespace

std::string trackerSettingKeys() {
    const TrackerSettings d;
    std::string levels, iterations, distances, steps;
    for (const TrackerLevel& l : d.levels) {
        levels += char(l.motion);
        iterations += " " + std::to_string(l.max_iterations);
        distances += " " + floatText(l.max_distance_m);
        steps += " " + std::to_string(l.pixel_step);
    }
    // Lines of a settings file: printed, they read back as the defaults.
    std::ostringstream out;
    auto line = [&](const std::string& key_value, const std::string& help) {
        out << key_value << std::string(key_value.size() < 36 ? 36 - key_value.size() : 1, ' ') << "# " << help << "\n";
    };
    line(std::string("tracker = ") + toString(d.kind), "icp | color | ren | rgbd");
    line("levels = " + levels, "pyramid levels coarse to fine: r rotation, t translation, b both");
    line("iterations =" + iterations, "per level, coarse to fine (one value: every level)");
    line("max_distance_m =" + distances, "ICP outlier distance per level (metres)");
    line("pixel_step =" + steps, "ICP terms from every n-th row and column, per level");
    line(d.color_weight_auto ? "color_weight = auto" : "color_weight = " + floatText(d.color_weight),
         "rgbd: weight of colour against depth, auto (by their noise) or m^2 per squared intensity");
    for (const TrackerSettingRow& row : kRows) {
        const std::string value = std::visit(
            [&](auto field) -> std::string {
                const auto& v = d.*field;
                using V = std::decay_t<decltype(v)>;
                if constexpr (std::is_same_v<V, float>)
                    return floatText(v);
                else if constexpr (std::is_same_v<V, int>)
                    return std::to_string(v);
                else if constexpr (std::is_same_v<V, bool>)
                    return v ? "true" : "false";
                else
                    return kernelName(v);
            },
            row.field);
        line(std::string(row.key) + " = " + value, row.help);
    }
    return out.str();
}

void validateTrackerSettings(const TrackerSettings& settings) {
    std::vector<std::string> keys;
    std::string reason;
    if (findInvalidSetting(settings, keys, reason))
        throw ConfigError("tracker setting " + keys.front() + ": " + reason);
}

namespace {

// "rbb": the level types, coarse to fine, as a settings file writes them.
std::string levelsText(const std::vector<TrackerLevel>& levels) {
    std::string text;
    for (const TrackerLevel& l : levels) text += char(l.motion);
    return text;
}

// Lines from `first_override_line` on are a front-end's single values (trackerSettingsWith): they may
// set a key the file set too; within the file a key set twice is an error (which one was meant?).
TrackerSettings parseTrackerSettingsText(const std::string& text, const std::string& name, int first_override_line) {
    TrackerSettings s;
    std::map<std::string, int> line_of;  // key -> line where it was set
    // Per-level lists are applied once the number of levels is known (after the last line).
    std::vector<double> iterations, distances, pixel_steps;

    // Finite as the float the setting keeps, not only as a double: 1e39 would become infinity.
    auto number = [](const std::string& v, double& out) {
        return text::parseDouble(v, out) && std::isfinite(out) && std::isfinite(float(out));
    };
    auto setFloat = [&](float& field) {
        return [&field, number](const std::string& v) -> std::string {
            double d;
            if (!number(v, d)) return "not a number (finite, in float range): '" + v + "'";
            field = float(d);
            return {};
        };
    };
    auto setInt = [&](int& field) {
        return [&field](const std::string& v) -> std::string {
            return text::parseInt(v, field) ? std::string() : "not an integer: '" + v + "'";
        };
    };
    auto setBool = [&](bool& field) {
        return [&field](const std::string& v) -> std::string {
            if (v == "true" || v == "on" || v == "1")
                field = true;
            else if (v == "false" || v == "off" || v == "0")
                field = false;
            else
                return "expected true or false, got '" + v + "'";
            return {};
        };
    };
    auto setKernel = [&](RobustKernel& field) {
        return [&field](const std::string& v) -> std::string {
            bool ok;
            field = parseKernel(v, ok);
            return ok ? std::string() : "unknown kernel '" + v + "' (expected none, huber or tukey)";
        };
    };
    auto setList = [&](std::vector<double>& list) {
        return [&list, number](const std::string& v) -> std::string {
            list.clear();
            for (std::string_view token : text::splitWhitespace(v)) {
                double d;
                if (!number(std::string(token), d))
                    return "not a number (finite, in float range): '" + std::string(token) + "'";
                list.push_back(d);
            }
            return {};
        };
    };

    std::map<std::string, std::function<std::string(const std::string&)>> setters = {
        {"tracker",
         [&](const std::string& v) -> std::string {
             try {
                 s.kind = parseTrackerKind(v);
             } catch (const ConfigError& e) {
                 return e.what();
             }
             return {};
         }},
        {"levels",
         [&](const std::string& v) -> std::string {
             for (char c : v)
                 if (c != 'r' && c != 't' && c != 'b')
                     return "level types are r (rotation), t (translation) or b (both), got '" + v + "'";
             if (v.empty() || v.size() > 8) return "need 1 to 8 levels, got '" + v + "'";
             s.levels = levelsFor(v);
             return {};
         }},
        {"iterations", setList(iterations)},
        {"max_distance_m", setList(distances)},
        {"pixel_step", setList(pixel_steps)},
        {"color_weight",
         [&](const std::string& v) -> std::string {
             double d;
             if (v == "auto") {
                 s.color_weight_auto = true;
             } else if (number(v, d)) {
                 s.color_weight_auto = false;
                 s.color_weight = float(d);
             } else {
                 return "expected auto or a number, got '" + v + "'";
             }
             return {};
         }},
    };
    for (const TrackerSettingRow& row : kRows)
        setters[row.key] = std::visit(
            [&](auto field) -> std::function<std::string(const std::string&)> {
                auto& value = s.*field;
                using V = std::decay_t<decltype(value)>;
                if constexpr (std::is_same_v<V, float>)
                    return setFloat(value);
                else if constexpr (std::is_same_v<V, int>)
                    return setInt(value);
                else if constexpr (std::is_same_v<V, bool>)
                    return setBool(value);
                else
                    return setKernel(value);
            },
            row.field);

    std::istringstream in(text);
    std::string line;
    int line_number = 0;
    while (std::getline(in, line)) {
        ++line_number;
        const auto hash = line.find('#');
        if (hash != std::string::npos) line.erase(hash);
        line = trim(line);
        if (line.empty()) continue;
        const auto eq = line.find('=');
        if (eq == std::string::npos) throw ParseError(name, line_number, "expected 'key = value', got '" + line + "'");
        const std::string key = trim(line.substr(0, eq)), value = trim(line.substr(eq + 1));
        const auto setter = setters.find(key);
        if (setter == setters.end()) throw ParseError(name, line_number, "unknown tracker setting '" + key + "'");
        if (value.empty()) throw ParseError(name, line_number, "no value for '" + key + "'");
        if (line_number < first_override_line && line_of.count(key))
            throw ParseError(name, line_number,
                             "'" + key + "' is set twice (first on line " + std::to_string(line_of[key]) + ")");
        const std::string error = setter->second(value);
        if (!error.empty()) throw ParseError(name, line_number, key + ": " + error);
        line_of[key] = line_number;
    }

    const std::size_t n = s.levels.size();
    auto applyList = [&](const char* key, const std::vector<double>& list, auto apply) {
        if (!line_of.count(key)) return;
        if (list.size() != 1 && list.size() != n)
            throw ParseError(name, line_of[key],
                             std::string(key) + ": expected 1 or " + std::to_string(n) +
                                 " values (one per level of levels = " + levelsText(s.levels) + "), got " +
                                 std::to_string(list.size()));
        for (std::size_t i = 0; i < n; ++i) apply(s.levels[i], list.size() == 1 ? list[0] : list[i]);
    };
    applyList("iterations", iterations, [&](TrackerLevel& l, double v) {
        if (v != std::floor(v) || v < 1 || v > 1000)
            throw ParseError(name, line_of["iterations"],
                             "iterations: expected integers in 1..1000, got " + formatNumber(v));
        l.max_iterations = int(v);
    });
    applyList("max_distance_m", distances, [](TrackerLevel& l, double v) { l.max_distance_m = float(v); });
    applyList("pixel_step", pixel_steps, [&](TrackerLevel& l, double v) {
        if (v != std::floor(v) || v < 1 || v > 8)
            throw ParseError(name, line_of["pixel_step"],
                             "pixel_step: expected integers in 1..8, got " + formatNumber(v));
        l.pixel_step = int(v);
    });

    std::vector<std::string> keys;
    std::string reason;
    if (findInvalidSetting(s, keys, reason)) {
        int line_at = line_number;  // the last of the involved keys the file set (else its last line)
        bool in_file = false;
        for (const std::string& k : keys)
            if (line_of.count(k)) {
                line_at = in_file ? std::max(line_at, line_of[k]) : line_of[k];
                in_file = true;
            }
        throw ParseError(name, line_at, keys.front() + ": " + reason);
    }
    return s;
}

}  // namespace

TrackerSettings parseTrackerSettings(const std::string& text, const std::string& name) {
    return parseTrackerSettingsText(text, name, INT_MAX);
}

TrackerSettings parseTrackerSettingsFile(const std::string& path) {
    return parseTrackerSettings(text::readSmallTextFile(path, "tracker settings file"), path);
}

TrackerSettings trackerSettingsWith(const TrackerOverrides& o) {
    std::string text, name = o.origin;
    if (!o.settings_file.empty()) {
        text = text::readSmallTextFile(o.settings_file, "tracker settings file") + "\n";
        name = o.settings_file;
    }
    const int file_lines = int(std::count(text.begin(), text.end(), '\n'));
    auto list = [](const auto& values) {
        std::ostringstream out;
        out.precision(9);
        for (const auto& v : values) out << " " << v;
        return out.str();
    };
    if (!o.kind.empty()) text += "tracker = " + o.kind + "\n";
    if (!o.levels.empty()) text += "levels = " + o.levels + "\n";
    if (!o.iterations.empty()) text += "iterations =" + list(o.iterations) + "\n";
    if (!o.max_distance_m.empty()) text += "max_distance_m =" + list(o.max_distance_m) + "\n";
    try {
        return parseTrackerSettingsText(text, name, file_lines + 1);
    } catch (const ParseError& e) {
        // A line after the file's is one of the single values: no line number to give for those.
        if (e.line() <= file_lines) throw;
        throw ConfigError(o.origin + (o.settings_file.empty() ? "" : " (over " + o.settings_file + ")") + ": " +
                          e.reason());
    }
}

}  // namespace voxfuse
