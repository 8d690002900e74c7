// Tracker settings: names, validation and the "key = value" settings file.

#include "voxfuse/engines/TrackerSettings.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <functional>
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
    if (!(s.max_normal_angle_deg > 0.f && s.max_normal_angle_deg <= 180.f))
        return fail({"max_normal_angle_deg"}, "must be in (0, 180]");
    if (!(s.min_rotation_step_rad >= 0.f)) return fail({"min_rotation_step_rad"}, "must be >= 0");
    if (!(s.min_translation_step_m >= 0.f)) return fail({"min_translation_step_m"}, "must be >= 0");
    if (!(s.max_normal_edge_m > 0.f)) return fail({"max_normal_edge_m"}, "must be > 0");
    if (!(s.max_tracking_depth_m >= 0.f && std::isfinite(s.max_tracking_depth_m)))
        return fail({"max_tracking_depth_m"}, "must be >= 0 (0: no limit)");
    // A share above 1/3 would call even normals pointing evenly everywhere poor.
    if (!(s.poor_translation_constraint >= 0.f && s.poor_translation_constraint < 1.f / 3.f))
        return fail({"poor_translation_constraint"}, "must be in [0, 1/3)");
    if (!(s.robust_scale_m > 0.f)) return fail({"robust_scale_m"}, "must be > 0");
    if (s.color_point_step < 1 || s.color_point_step > 16) return fail({"color_point_step"}, "must be in 1..16");
    if (!(s.color_kernel_scale > 0.f)) return fail({"color_kernel_scale"}, "must be > 0");
    if (!(s.color_weight >= 0.f && std::isfinite(s.color_weight))) return fail({"color_weight"}, "must be >= 0");
    if (s.far_field_keyframes < 0 || s.far_field_keyframes > 16)
        return fail({"far_field_keyframes"}, "must be in 0..16 (0: off)");
    if (!(s.far_field_spacing_m >= 0.f && std::isfinite(s.far_field_spacing_m)))
        return fail({"far_field_spacing_m"}, "must be >= 0");
    if (!(s.far_field_spacing_deg >= 0.f && std::isfinite(s.far_field_spacing_deg)))
        return fail({"far_field_spacing_deg"}, "must be >= 0");
    if (!(s.far_field_point_share > 0.f && s.far_field_point_share <= 1.f))
        return fail({"far_field_point_share"}, "must be in (0, 1]");
    for (auto [key, v] : {std::pair{"good_inlier_ratio", s.good_inlier_ratio},
                          {"failed_inlier_ratio", s.failed_inlier_ratio},
                          {"good_condition", s.good_condition},
                          {"failed_condition", s.failed_condition}})
        if (!(v >= 0.f && v <= 1.f)) return fail({key}, "must be in [0, 1]");
    if (s.failed_inlier_ratio > s.good_inlier_ratio)
        return fail({"failed_inlier_ratio", "good_inlier_ratio"},
                    "failed_inlier_ratio must not exceed good_inlier_ratio");
    if (s.failed_condition > s.good_condition)
        return fail({"failed_condition", "good_condition"}, "failed_condition must not exceed good_condition");
    if (!(s.poor_residual_m > 0.f)) return fail({"poor_residual_m"}, "must be > 0");
    if (!(s.failed_color_residual > 0.f)) return fail({"failed_color_residual"}, "must be > 0");
    if (s.min_inliers < 6) return fail({"min_inliers"}, "must be >= 6 (a pose has 6 parameters)");
    if (!(s.max_motion_m > 0.f)) return fail({"max_motion_m"}, "must be > 0");
    if (!(s.max_motion_deg > 0.f && s.max_motion_deg <= 180.f)) return fail({"max_motion_deg"}, "must be in (0, 180]");
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

    const std::map<std::string, std::function<std::string(const std::string&)>> setters = {
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
        {"max_normal_angle_deg", setFloat(s.max_normal_angle_deg)},
        {"min_rotation_step_rad", setFloat(s.min_rotation_step_rad)},
        {"min_translation_step_m", setFloat(s.min_translation_step_m)},
        {"bilateral_filter", setBool(s.bilateral_filter)},
        {"predict_motion", setBool(s.predict_motion)},
        {"extrapolate_steps", setBool(s.extrapolate_steps)},
        {"max_normal_edge_m", setFloat(s.max_normal_edge_m)},
        {"max_tracking_depth_m", setFloat(s.max_tracking_depth_m)},
        {"robust_kernel", setKernel(s.robust_kernel)},
        {"robust_scale_m", setFloat(s.robust_scale_m)},
        {"color_point_step", setInt(s.color_point_step)},
        {"color_kernel", setKernel(s.color_kernel)},
        {"color_kernel_scale", setFloat(s.color_kernel_scale)},
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
        {"color_from_map", setBool(s.color_from_map)},
        {"far_field_keyframes", setInt(s.far_field_keyframes)},
        {"far_field_spacing_m", setFloat(s.far_field_spacing_m)},
        {"far_field_spacing_deg", setFloat(s.far_field_spacing_deg)},
        {"far_field_point_share", setFloat(s.far_field_point_share)},
        {"good_inlier_ratio", setFloat(s.good_inlier_ratio)},
        {"failed_inlier_ratio", setFloat(s.failed_inlier_ratio)},
        {"good_condition", setFloat(s.good_condition)},
        {"failed_condition", setFloat(s.failed_condition)},
        {"poor_translation_constraint", setFloat(s.poor_translation_constraint)},
        {"poor_residual_m", setFloat(s.poor_residual_m)},
        {"failed_color_residual", setFloat(s.failed_color_residual)},
        {"min_inliers", setInt(s.min_inliers)},
        {"max_motion_m", setFloat(s.max_motion_m)},
        {"max_motion_deg", setFloat(s.max_motion_deg)},
    };

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
