// voxfuse.Settings, voxfuse.Pipeline and voxfuse.FrameResult: the reconstruction loop fed NumPy frames.
// Input arrays are checked (dtype: TypeError; shape: ValueError) and copied once into the engine's
// frame buffer; the GIL is released while the engine works.

#include <pybind11/stl.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstring>
#include <optional>
#include <sstream>

#include "Bindings.h"
#include "MapOutputs.h"
#include "NumpyArrays.h"
#include "Pipeline.h"
#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/MapFile.h"

namespace voxfuse::python {

namespace {

struct FrameOutcome {
    FrameResult result;
    int index = 0;
    double timestamp_s = 0.0;
};

std::string typeText(const SettingRow& row) {
    return std::visit(
        [](auto member) -> std::string {
            using T = std::decay_t<decltype(PipelineSettings{}.*member)>;
            if constexpr (std::is_same_v<T, bool>) return "bool";
            if constexpr (std::is_same_v<T, int>) return "int";
            if constexpr (std::is_same_v<T, float>) return "float";
            if constexpr (std::is_same_v<T, std::string>) return "str";
            if constexpr (std::is_same_v<T, std::vector<int>>) return "list of int";
            return "list of float";
        },
        row.member);
}

bool isInteger(const py::handle& v) { return PyIndex_Check(v.ptr()) && !PyBool_Check(v.ptr()); }
// Python and NumPy numbers alike (numpy.float32 is no float subclass); not text, not a bool.
bool isNumber(const py::handle& v) {
    return PyNumber_Check(v.ptr()) && !PyBool_Check(v.ptr()) && !py::isinstance<py::str>(v);
}

// `value` as the row's type: TypeError when it is of another kind; numbers too large for their type
// are out of range (ConfigError from the row's check).
void setSetting(const SettingRow& row, PipelineSettings& s, const py::handle& value) {
    const auto wrong = [&] {
        return py::type_error("setting '" + std::string(row.name) + "' cannot be " + std::string(py::repr(value)) +
                              " (a " + typeText(row) + "; see help(voxfuse.Settings))");
    };
    auto number = [&](const py::handle& v, auto zero) {
        using T = decltype(zero);
        if constexpr (std::is_same_v<T, int>) {
            if (!isInteger(v)) throw wrong();
            const long long wide = py::int_(py::reinterpret_borrow<py::object>(v)).cast<long long>();
            if (wide < INT_MIN || wide > INT_MAX)
                throw ConfigError("setting '" + std::string(row.name) + "': " + std::to_string(wide) +
                                  " is out of range");
            return int(wide);
        } else {
            if (!isNumber(v)) throw wrong();
            return float(py::float_(py::reinterpret_borrow<py::object>(v)).cast<double>());  // 1e39: inf, refused
        }
    };
    PipelineSettings changed = s;
    std::visit(
        [&](auto member) {
            auto& field = changed.*member;
            using T = std::decay_t<decltype(field)>;
            if constexpr (std::is_same_v<T, bool>) {
                if (!PyBool_Check(value.ptr()) && !py::isinstance(value, py::module_::import("numpy").attr("bool_")))
                    throw wrong();
                field = PyObject_IsTrue(value.ptr()) == 1;
            } else if constexpr (std::is_same_v<T, int> || std::is_same_v<T, float>) {
                field = number(value, T());
            } else if constexpr (std::is_same_v<T, std::string>) {
                py::object text = py::reinterpret_borrow<py::object>(value);
                if (py::hasattr(text, "__fspath__")) text = text.attr("__fspath__")();  // a pathlib.Path
                if (!py::isinstance<py::str>(text)) throw wrong();
                field = text.cast<std::string>();
            } else {
                if (py::isinstance<py::str>(value) || !py::isinstance<py::sequence>(value)) throw wrong();
                T values;
                for (const py::handle item : py::reinterpret_borrow<py::sequence>(value))
                    values.push_back(number(item, typename T::value_type()));
                field = std::move(values);
            }
        },
        row.member);
    if (std::string why = settingProblem(row, changed); !why.empty())
        throw ConfigError("setting '" + std::string(row.name) + "': " + why);
    s = std::move(changed);
}

// Floats as the decimals they were given as (0.005, not 0.004999999888).
py::object settingValue(const SettingRow& row, const PipelineSettings& s) {
    return std::visit(
        [&](auto member) -> py::object {
            const auto& value = s.*member;
            using T = std::decay_t<decltype(value)>;
            if constexpr (std::is_same_v<T, float>) {
                return py::float_(floatAsDecimal(value));
            } else if constexpr (std::is_same_v<T, std::vector<float>>) {
                py::list list;
                for (const float v : value) list.append(floatAsDecimal(v));
                return list;
            } else {
                return py::cast(value);
            }
        },
        row.member);
}

// The row for a keyword: its name, or a former spelling (with a DeprecationWarning); TypeError otherwise.
const SettingRow& rowForKeyword(const std::string& name) {
    if (const SettingRow* row = findSettingRow(name)) return *row;
    for (const SettingRow& row : pipelineSettingRows())
        if (name == row.former_name) {
            const std::string text = name + " is now " + row.name;
            if (PyErr_WarnEx(PyExc_DeprecationWarning, text.c_str(), 1) < 0) throw py::error_already_set();
            return row;
        }
    throw py::type_error("unknown setting '" + name + "' (see voxfuse.Settings)");
}

// Settings from keyword arguments over `base`.
PipelineSettings withOverrides(PipelineSettings base, const py::kwargs& overrides) {
    if (!overrides) return base;
    for (const auto& item : overrides) setSetting(rowForKeyword(py::str(item.first)), base, item.second);
    return base;
}

// The docstring of a setting: what it does, its type, range or choices, and default.
std::string settingDoc(const SettingRow& row) {
    std::string doc = settingDescription(row) + ".\n" + typeText(row);
    if (*row.choices) doc += ": one of " + std::string(row.choices);
    const std::string type = typeText(row);
    if (type != "bool" && type != "str") {
        std::ostringstream range;
        range << ", in " << (row.min_open ? "(" : "[") << row.min << ", " << row.max << "]";
        doc += range.str();
    }
    return doc + "; default " + std::string(py::repr(settingValue(row, PipelineSettings{}))) + ".";
}

void checkShape(const py::array& a, const char* what, py::ssize_t h, py::ssize_t w, const char* channels_text,
                bool channels_ok) {
    if (a.ndim() < 2 || a.shape(0) != h || a.shape(1) != w || !channels_ok)
        throw py::value_error(std::string(what) + " must be of shape (" + std::to_string(h) + ", " + std::to_string(w) +
                              channels_text + ") for this calibration, not " + shapeText(a));
}

}  // namespace

// `raw_scale` > 0: uint16 depth in units of that many metres (converted to the calibration's units).
void copyDepth(const py::handle& value, const RGBDCalib& calib, float raw_scale, Image<std::uint16_t>& out) {
    if (!py::isinstance<py::array>(value))
        throw py::type_error("depth must be a numpy array (uint16 raw, or float32/float64 metres)");
    const py::array a = py::reinterpret_borrow<py::array>(value);
    const py::ssize_t h = calib.depth.height, w = calib.depth.width;
    checkShape(a, "depth", h, w, "", a.ndim() == 2);
    out.resize({int(w), int(h)});
    std::uint16_t* dst = out.host();
    const bool is_raw = py::isinstance<py::array_t<std::uint16_t>>(a);
    if (!is_raw && raw_scale > 0.f)
        throw py::type_error("depth_scale applies to uint16 depth; float depth is in metres already");
    if (is_raw && raw_scale <= 0.f) {
        const auto raw = py::array_t<std::uint16_t, py::array::c_style>::ensure(a);
        std::copy_n(raw.data(), std::size_t(h * w), dst);
        return;
    }
    if (!is_raw && !py::isinstance<py::array_t<float>>(a) && !py::isinstance<py::array_t<double>>(a))
        throw py::type_error("depth must be uint16 (raw) or float32/float64 (metres), not " +
                             std::string(py::str(a.dtype())));
    // Metres become raw units of the calibration's scale (0.2 mm for TUM's, 1 mm by default); what the
    // raw range cannot hold, NaN and non-positive values are "no measurement".
    const double to_calib_units = (is_raw ? double(raw_scale) : 1.0) / double(metresPerRawUnit(calib));
    auto convert = [&](auto element) {  // in the array's own element type: no converted copy first
        using T = decltype(element);
        const auto values = py::array_t<T, py::array::c_style>::ensure(a);
        const T* src = values.data();
        for (py::ssize_t i = 0; i < h * w; ++i) {
            const double raw = std::round(double(src[i]) * to_calib_units);
            dst[i] = raw >= 1.0 && raw <= 65535.0 ? std::uint16_t(raw) : 0;  // NaN fails both tests
        }
    };
    if (is_raw)
        convert(std::uint16_t());
    else if (py::isinstance<py::array_t<float>>(a))
        convert(float());
    else
        convert(double());
}

void copyRgb(const py::handle& value, const RGBDCalib& calib, Image<Vec4u8>& out) {
    if (!py::isinstance<py::array_t<std::uint8_t>>(value))
        requireDtype<std::uint8_t>(value, "rgb", "uint8 (H, W, 3) or (H, W, 4)");
    const py::array a = py::reinterpret_borrow<py::array>(value);
    const Intrinsics& cam = calib.rgb.valid() ? calib.rgb : calib.depth;
    const py::ssize_t h = cam.height, w = cam.width;
    checkShape(a, "rgb", h, w, ", 3 or 4", a.ndim() == 3 && (a.shape(2) == 3 || a.shape(2) == 4));
    out.resize({int(w), int(h)});
    Vec4u8* dst = out.host();
    const py::ssize_t c = a.shape(2), sy = a.strides(0), sx = a.strides(1), sc = a.strides(2);
    const auto* base = static_cast<const std::uint8_t*>(a.data());
    // Read in place whatever the strides (no contiguous copy first): a frame's own RGB view of RGBA
    // pixels, an RGB or RGBA image, a crop or a transposed array alike.
    for (py::ssize_t y = 0; y < h; ++y) {
        const std::uint8_t* row = base + y * sy;
        Vec4u8* out_row = dst + y * w;
        if (sc == 1 && sx == 4) {  // 4-byte pixels (RGBA, or RGB viewed through RGBA): whole rows
            // An RGB view ends 3 bytes into its last pixel: that pixel is copied alone, never its 4th byte
            // (which may lie past the end of the buffer).
            std::memcpy(static_cast<void*>(out_row), row, std::size_t(4 * (c == 4 ? w : w - 1)));
            if (c == 3) {
                for (py::ssize_t x = 0; x + 1 < w; ++x) out_row[x].w = 255;
                const std::uint8_t* last = row + 4 * (w - 1);
                out_row[w - 1] = {last[0], last[1], last[2], 255};
            }
        } else {
            for (py::ssize_t x = 0; x < w; ++x) {
                const std::uint8_t* px = row + x * sx;
                out_row[x] = {px[0], px[sc], px[2 * sc], c == 4 ? px[3 * sc] : std::uint8_t(255)};
            }
        }
    }
}

namespace {

void copyLabels(const py::handle& value, Image<ClassId>& out) {
    const auto a = requireDtype<ClassId>(value, "labels", "uint16 (H, W)");
    if (a.ndim() != 2)
        throw py::value_error("labels must be a 2-D (H, W) array of class ids, not of shape " + shapeText(a));
    out.resize({int(a.shape(1)), int(a.shape(0))});
    std::copy_n(a.data(), std::size_t(a.size()), out.host());
}

RenderMode parseRenderMode(const std::string& mode) {
    if (mode == "shaded") return RenderMode::Shaded;
    if (mode == "color" || mode == "colour") return RenderMode::Color;
    if (mode == "normals") return RenderMode::Normals;
    if (mode == "depth") return RenderMode::Depth;
    if (mode == "class") return RenderMode::Class;
    throw ConfigError("render mode: shaded, color, normals, depth or class, not '" + mode + "'");
}

py::dict stageDict(const std::vector<StageTime>& stages, double total_ms) {
    py::dict d;
    for (const StageTime& s : stages) d[s.stage] = s.ms;
    d["total"] = total_ms;
    return d;
}

double median(std::vector<double> v) {
    if (v.empty()) return std::nan("");
    const std::size_t mid = v.size() / 2;
    std::nth_element(v.begin(), v.begin() + long(mid), v.end());
    const double upper = v[mid];
    if (v.size() % 2) return upper;
    return 0.5 * (upper + *std::max_element(v.begin(), v.begin() + long(mid)));
}

// Loop closures (or a merge's joins) as dicts: frame, from_submap, to_submap, residual_m, inlier_ratio,
// chi2, rejected.
py::list loopDicts(const std::vector<LoopClosure>& loops) {
    py::list out;
    for (const LoopClosure& l : loops) {
        py::dict d;
        d["frame"] = l.frame;
        d["from_submap"] = l.from_submap;
        d["to_submap"] = l.to_submap;
        d["residual_m"] = l.residual_m;
        d["inlier_ratio"] = l.inlier_ratio;
        d["chi2"] = l.chi2;
        d["rejected"] = l.rejected;
        out.append(d);
    }
    return out;
}

py::dict timings(const Pipeline& p) {
    py::dict d;
    for (const auto& [stage, t] : p.stageTimes()) {
        double sum = 0.0;
        for (double ms : t.ms) sum += ms;
        py::dict s;
        s["median_ms"] = median(t.ms);
        s["mean_ms"] = t.ms.empty() ? std::nan("") : sum / double(t.ms.size());
        s["frames"] = t.ms.size();
        d[stage.c_str()] = s;
    }
    return d;
}

// A mesh or cloud of the map, made without the GIL, with the channels its voxel type has.
template <class TOutput, class TGeometry>
TOutput extractOutput(Pipeline& p, const char* call, void (MainEngine::*extract)(TGeometry&)) {
    auto geometry = std::make_shared<TGeometry>();
    const auto busy = p.claim(call);
    {
        py::gil_scoped_release no_gil;
        (p.engine().*extract)(*geometry);
    }
    const VoxelType t = p.engine().settings().voxel_type;
    return {geometry, voxelTypeHasColor(t), voxelTypeHasLabels(t)};
}

py::array render(Pipeline& p, const std::string& mode, const py::object& pose,
                 const std::optional<Intrinsics>& intrinsics) {
    const RenderMode m = parseRenderMode(mode);
    const auto busy = p.claim("render");
    Image<Vec4u8> image;
    if (pose.is_none()) {
        if (intrinsics)
            throw ConfigError("render: intrinsics need a pose (without one, the last frame's raycast is shown)");
        py::gil_scoped_release no_gil;
        p.engine().renderLast(m, image);
    } else {
        const Mat4f T = arrayToMatrix(pose, "pose");
        const Intrinsics k = intrinsics ? *intrinsics : p.calib().depth;
        if (!k.valid()) throw ConfigError("render: the intrinsics need a positive size and focal lengths");
        py::gil_scoped_release no_gil;
        p.engine().renderFromPose(T, k, m, image);
    }
    return imageToArray<std::uint8_t>(std::move(image), 3);
}

py::dict summary(Pipeline& p) {
    const MainEngineSettings& s = p.engine().settings();
    py::dict d;
    d["device"] = deviceName(s.device);
    if (s.device == Device::CUDA) d["gpu"] = device_memory::cudaDescription();
    d["voxel"] = toString(s.voxel_type);
    d["index"] = toString(s.index_type);
    d["voxel_size_m"] = s.scene.voxel_size_m;
    d["frames"] = p.framesProcessed();
    d["frames_fused"] = p.framesFused();
    d["frames_failed"] = p.framesFailed();
    d["frames_poor"] = p.framesPoor();
    d["frames_lost"] = p.framesLost();
    d["relocalisation_attempts"] = p.relocalisationAttempts();
    d["relocalisations"] = p.relocalisations();
    const auto total = p.stageTimes().find("total");
    const double total_median = total == p.stageTimes().end() ? std::nan("") : median(total->second.ms);
    d["median_frame_ms"] = total_median;
    d["frames_per_s"] = 1000.0 / total_median;
    d["stages"] = timings(p);
    d["scene_mb"] = double(p.engine().sceneBytes()) / (1024.0 * 1024.0);
    const AllocationStats a = p.engine().allocationStats();
    d["blocks_in_use"] = a.blocks_allocated;
    d["blocks_stored"] = a.blocks_stored;
    d["allocation_failures"] = a.allocation_failures_total;
    return d;
}

}  // namespace

void bindPipeline(py::module_& m) {
    py::class_<PipelineSettings> settings(
        m, "Settings",
        "Pipeline settings, with the names (underscores for dashes), defaults and checks of `voxfuse --help`:\n"
        "both are made from one table (Settings.table()).\n"
        "Settings(voxel_size=0.01, tracker='rgbd'); any of them can also be given to Pipeline(...).");
    settings.def(py::init([](const py::kwargs& kwargs) { return withOverrides(PipelineSettings{}, kwargs); }));
    for (const SettingRow& row : pipelineSettingRows())
        settings.def_property(
            row.name, [&row](const PipelineSettings& s) { return settingValue(row, s); },
            [&row](PipelineSettings& s, const py::object& value) { setSetting(row, s, value); },
            settingDoc(row).c_str());
    settings
        .def(
            "to_dict",
            [](const PipelineSettings& s) {
                py::dict d;
                for (const SettingRow& row : pipelineSettingRows()) d[row.name] = settingValue(row, s);
                return d;
            },
            "Every setting by name.")
        .def_static(
            "table",
            [] {
                py::list rows;
                for (const SettingRow& row : pipelineSettingRows()) {
                    py::dict r;
                    r["name"] = row.name;
                    r["option"] = optionName(row);
                    r["type"] = typeText(row);
                    r["default"] = settingValue(row, PipelineSettings{});
                    r["unit"] = row.unit;
                    r["min"] = row.min;
                    r["max"] = row.max;
                    r["min_open"] = row.min_open;
                    r["choices"] = row.choices;
                    r["help"] = row.help;
                    rows.append(r);
                }
                return rows;
            },
            "The settings table: per setting its name, command-line option, type, default, unit, range, choices "
            "and help.")
        .def("__repr__", [](const py::object& self) {
            return "voxfuse.Settings(**" + std::string(py::repr(self.attr("to_dict")())) + ")";
        });

    py::class_<FrameOutcome>(m, "FrameResult", "What Pipeline.process did with one frame.")
        .def_property_readonly(
            "pose", [](const FrameOutcome& o) { return matrixToArray(o.result.T_world_camera); },
            "Camera-to-world pose (4, 4); after a failure, the last good pose.")
        .def_property_readonly(
            "quality", [](const FrameOutcome& o) { return toString(o.result.quality); }, "'good', 'poor' or 'failed'.")
        .def_property_readonly(
            "fused", [](const FrameOutcome& o) { return o.result.fused; },
            "Whether the frame went into the map (a failed frame does not).")
        .def_property_readonly(
            "status", [](const FrameOutcome& o) { return toString(o.result.status); },
            "'tracking' (posed from the last frame, or given), 'lost' (no pose: the pose is the last good one,\n"
            "the frame was not fused and is not in the trajectory) or 'relocalised' (found again from keyframes).")
        .def_property_readonly(
            "relocalisation_tried", [](const FrameOutcome& o) { return o.result.relocalisation_tried; },
            "Whether the frame was looked up among the keyframes (tracking had failed or was lost).")
        .def_property_readonly(
            "keyframes", [](const FrameOutcome& o) { return o.result.keyframes; },
            "Keyframes the relocaliser holds after this frame.")
        .def_property_readonly("inlier_ratio", [](const FrameOutcome& o) { return o.result.tracking.inlier_ratio; })
        .def_property_readonly(
            "residual", [](const FrameOutcome& o) { return o.result.tracking.residual_m; },
            "RMS point-to-plane residual of the inliers (m; colour tracker: intensity).")
        .def_property_readonly(
            "condition", [](const FrameOutcome& o) { return o.result.tracking.condition; },
            "Smallest/largest eigenvalue of the scaled normal matrix (near 0: a motion is unconstrained).")
        .def_property_readonly(
            "translation_constraint", [](const FrameOutcome& o) { return o.result.tracking.translation_constraint; },
            "Share of the depth terms' weight along the least constrained translation (0..1/3, below 0.02 poor; -1 "
            "without depth terms).")
        .def_property_readonly(
            "timings", [](const FrameOutcome& o) { return stageDict(o.result.stages, o.result.total_ms); },
            "Milliseconds per stage of this frame, and 'total'.")
        .def_readonly("index", &FrameOutcome::index)
        .def_readonly("timestamp", &FrameOutcome::timestamp_s)
        .def("__repr__", [](const FrameOutcome& o) {
            const std::string status =
                o.result.status == TrackingStatus::Tracking ? "" : std::string(", ") + toString(o.result.status);
            return "<voxfuse.FrameResult " + std::to_string(o.index) + ": " + toString(o.result.quality) + status +
                   (o.result.fused ? ", fused" : "") + ">";
        });

    py::class_<Pipeline>(
        m, "Pipeline",
        "The reconstruction loop: each frame is tracked against the model (or placed at a given pose), fused\n"
        "into the TSDF map and the model is raycast from the new pose.\n\n"
        "    pipeline = voxfuse.Pipeline(source.calib, voxel_size=0.01)\n"
        "    for frame in source:\n"
        "        result = pipeline.process(frame.depth, frame.rgb)\n"
        "    pipeline.extract_mesh().save('mesh.ply')\n\n"
        "Settings are voxfuse.Settings names (those of `voxfuse --help`), given as a Settings or as keywords.")
        .def(py::init([](const RGBDCalib& calib, const std::optional<PipelineSettings>& s, const py::kwargs& kwargs) {
                 const PipelineSettings settings = withOverrides(s ? *s : PipelineSettings{}, kwargs);
                 py::gil_scoped_release no_gil;
                 return std::make_unique<Pipeline>(calib, settings);
             }),
             py::arg("calib"), py::arg("settings") = py::none())
        .def_static(
            "from_map",
            [](const std::string& path, const std::optional<RGBDCalib>& calib, const std::optional<PipelineSettings>& s,
               const py::kwargs& kwargs) {
                for (const char* fixed : {"voxel", "index", "voxel_size", "mu", "hash_buckets", "hash_excess",
                                          "volume_size", "volume_offset"})
                    if (kwargs.contains(fixed))
                        throw ConfigError(path + ": the map decides '" + fixed +
                                          "'; leave it out (or create a Pipeline and load_map)");
                const MapFileInfo info = readMapFileInfo(path);
                PipelineSettings settings = withOverrides(s ? *s : PipelineSettings{}, kwargs);
                settings.adopt(info);
                // The block ceiling bounds how far the map may grow here: the map's, unless given.
                if (kwargs.contains("max_blocks")) settings.max_blocks = kwargs["max_blocks"].cast<int>();
                RGBDCalib c;
                if (calib)
                    c = *calib;
                else {
                    if (!info.camera.valid()) throw ConfigError(path + ": the map has no camera; give a calib");
                    c.depth = c.rgb = info.camera;
                }
                py::gil_scoped_release no_gil;
                auto p = std::make_unique<Pipeline>(c, settings);
                p->engine().loadMap(path);
                return p;
            },
            py::arg("path"), py::arg("calib") = py::none(), py::arg("settings") = py::none(),
            "A pipeline continuing the map in a .vfm file (its voxel type, index, voxel size and mu, and its block "
            "ceiling\n"
            "unless max_blocks is given; tracking resumes\n"
            "from the pose it was saved at). Without calib: the camera the map was saved with, and raw depth in\n"
            "millimetres (depth given in metres is exact either way); give the source's calib to fuse its raw frames.")
        .def(
            "process",
            [](Pipeline& p, const py::handle& depth, const py::object& rgb, const py::object& labels,
               const py::object& depth_scale, const py::object& pose, const py::object& timestamp) {
                float raw_scale = 0.f;
                if (!depth_scale.is_none()) {
                    raw_scale = depth_scale.cast<float>();
                    if (!(raw_scale > 0.f) || !std::isfinite(raw_scale))
                        throw py::value_error("depth_scale must be a positive number of metres");
                }
                const auto busy = p.claim("process");
                RGBDFrame& f = p.frameBuffer();
                copyDepth(depth, p.calib(), raw_scale, f.depth_raw);
                if (rgb.is_none())
                    f.rgb = Image<Vec4u8>();
                else
                    copyRgb(rgb, p.calib(), f.rgb);
                if (labels.is_none()) {
                    f.labels = Image<ClassId>();
                } else {
                    copyLabels(labels,
                               f.labels);  // checked first: a wrong dtype or shape says so whatever the voxel type
                    // Labels given to a map that cannot hold them would be dropped without a word.
                    if (!voxelTypeHasLabels(p.engine().settings().voxel_type))
                        throw ConfigError(std::string("process: labels need a voxel type with classes (s_label, "
                                                      "s_rgb_label); this pipeline's is ") +
                                          toString(p.engine().settings().voxel_type));
                }
                std::optional<Mat4f> given;
                if (!pose.is_none()) given = arrayToMatrix(pose, "pose");
                f.index = p.framesProcessed();
                f.timestamp_s = timestamp.is_none() ? double(f.index) / 30.0 : timestamp.cast<double>();
                if (!std::isfinite(f.timestamp_s))
                    throw py::value_error("timestamp must be a finite number of seconds");  // the trajectory's key
                f.has_ground_truth = false;
                f.depth_path = "frame " + std::to_string(f.index) + " given to Pipeline.process";
                f.labels_path = f.depth_path;
                FrameOutcome o;
                o.index = f.index;
                o.timestamp_s = f.timestamp_s;
                py::gil_scoped_release no_gil;
                o.result = p.process(f, given ? &*given : nullptr);
                return o;
            },
            py::arg("depth"), py::arg("rgb") = py::none(), py::arg("labels") = py::none(), py::kw_only(),
            py::arg("depth_scale") = py::none(), py::arg("pose") = py::none(), py::arg("timestamp") = py::none(),
            "Processes one frame. depth: uint16 (H, W) raw (metres = raw * depth_scale, by default calib.depth_scale)\n"
            "or float32/float64 metres;\n"
            "rgb: uint8 (H, W, 3) or (H, W, 4) of the colour camera; labels: uint16 (H, W) class ids (65535: none).\n"
            "pose: a camera-to-world 4x4 to fuse at (e.g. ground truth) instead of tracking. timestamp: seconds\n"
            "(default: frame number / 30). Returns a FrameResult; a frame whose tracking failed is not fused.")
        .def(
            "process_frame",
            [](Pipeline& p, const std::shared_ptr<RGBDFrame>& frame, const py::object& pose, bool ground_truth) {
                std::optional<Mat4f> given;
                if (!pose.is_none() && ground_truth)
                    throw ConfigError("process_frame: give a pose or ground_truth=True, not both");
                if (!pose.is_none()) given = arrayToMatrix(pose, "pose");
                const auto busy = p.claim("process_frame");
                if (ground_truth) given = p.groundTruthPose(*frame);
                FrameOutcome o;
                o.index = frame->index;
                o.timestamp_s = frame->timestamp_s;
                py::gil_scoped_release no_gil;
                o.result = p.process(*frame, given ? &*given : nullptr);
                return o;
            },
            py::arg("frame"), py::kw_only(), py::arg("pose") = py::none(), py::arg("ground_truth") = false,
            "Processes a Frame from a Source as it is (no copy of its images), with its labels when it has any.\n"
            "pose: a camera-to-world 4x4 to fuse at instead of tracking; ground_truth=True: the frame's ground-truth\n"
            "pose, relative to the first frame's as `voxfuse --poses groundtruth` does.")
        .def(
            "render", &render, py::arg("mode") = "shaded", py::kw_only(), py::arg("pose") = py::none(),
            py::arg("intrinsics") = py::none(),
            "The model as an image, uint8 (H, W, 3) RGB (a view of RGBA pixels). mode: shaded, color, normals, depth "
            "or\n"
            "class. Without pose: the raycast of the last frame; with a camera-to-world pose (and intrinsics, default\n"
            "the depth camera's): a new raycast from there.")
        .def(
            "extract_mesh",
            [](Pipeline& p) { return extractOutput<MeshOutput>(p, "extract_mesh", &MainEngine::extractMesh); },
            "The map's surface by marching cubes, as a voxfuse.Mesh.")
        .def(
            "extract_point_cloud",
            [](Pipeline& p) {
                return extractOutput<CloudOutput>(p, "extract_point_cloud", &MainEngine::extractPointCloud);
            },
            "The map's surface points, as a voxfuse.PointCloud.")
        .def(
            "save_map",
            [](Pipeline& p, const std::string& path) {
                const auto busy = p.claim("save_map");
                py::gil_scoped_release no_gil;
                p.engine().saveMap(path);
            },
            py::arg("path"),
            "Writes the map and the current pose to a .vfm file (written to a temporary file, then renamed).")
        .def(
            "load_map",
            [](Pipeline& p, const std::string& path) {
                const auto busy = p.claim("load_map");
                py::gil_scoped_release no_gil;
                p.engine().loadMap(path);
            },
            py::arg("path"),
            "Replaces the map with a .vfm file's (which must match the settings; see Pipeline.from_map).")
        .def(
            "merge_map",
            [](Pipeline& p, const std::string& path) {
                const auto busy = p.claim("merge_map");
                std::vector<LoopClosure> joins;
                {
                    py::gil_scoped_release no_gil;
                    joins = p.engine().mergeMap(path);
                }
                return loopDicts(joins);
            },
            py::arg("path"),
            "Joins another map of the same place, made separately (a .vfm of this map's voxel type, voxel size and "
            "mu), as submaps of this one (submaps=True): its views are recognised here and verified as "
            "relocalisation verifies a pose. Returns the joins as loop_closures() describes them (frame -1). "
            "Raises Error when no view of it is found here (the map is unchanged then).")
        .def(
            "reset",
            [](Pipeline& p) {
                const auto busy = p.claim("reset");
                py::gil_scoped_release no_gil;  // a large dense volume takes a while to clear
                p.reset();
            },
            "Clears the map, the pose, the trajectory and the timings.")
        // The readers claim the pipeline too: a frame being processed on another thread appends to
        // what they copy (the trajectory, the stage times), and the engine's state is mid-update.
        .def_property_readonly(
            "pose",
            [](Pipeline& p) {
                const auto busy = p.claim("pose");
                return matrixToArray(p.engine().trackingState().T_world_camera);
            },
            "The current camera-to-world pose (4, 4).")
        .def_property_readonly(
            "trajectory",
            [](Pipeline& p) {
                const auto busy = p.claim("trajectory");
                return timedPosesToArrays(p.trajectory());
            },
            "(timestamps (N,), camera-to-world poses (N, 4, 4)) of every processed frame that has a pose (lost frames "
            "have none).")
        .def_property_readonly(
            "optimised_trajectory",
            [](Pipeline& p) {
                const auto busy = p.claim("optimised_trajectory");
                return timedPosesToArrays(p.optimisedTrajectory());
            },
            "The trajectory's frames at their submaps' poses as the pose graph optimised them (submaps=True; waits "
            "for a solve in progress); without submaps the trajectory itself.")
        .def_property_readonly(
            "submap_count",
            [](Pipeline& p) {
                const auto busy = p.claim("submap_count");
                return p.engine().submapCount();
            },
            "The submaps the map holds (1 without submaps).")
        .def(
            "submap_poses",
            [](Pipeline& p) {
                const auto busy = p.claim("submap_poses");
                py::list submaps;
                for (const SubmapPose& m : p.engine().submapPoses()) {
                    py::dict d;
                    d["pose"] = matrixToArray(m.T_world_submap);
                    d["parent"] = m.parent;
                    submaps.append(d);
                }
                return submaps;
            },
            "Every submap as the map places it now (submaps=True; empty without): dicts of pose (the submap-to-world "
            "pose (4, 4), the pose graph's last solution the map adopted) and parent (the submap it started from, "
            "joined by odometry; -1 for the first).")
        .def(
            "loop_closures",
            [](Pipeline& p) {
                const auto busy = p.claim("loop_closures");
                return loopDicts(p.engine().loopClosures());
            },
            "Every loop closure between submaps so far, as dicts: frame (processed frames before it since the map "
            "began), from_submap (the older one the camera was found in), to_submap, residual_m, inlier_ratio, chi2 "
            "(its pose graph edge's squared Mahalanobis residual) and rejected (dropped by the pose graph).")
        .def(
            "pose_graph_solves",
            [](Pipeline& p) {
                const auto busy = p.claim("pose_graph_solves");
                const PoseGraphSolveStats s = p.engine().poseGraphSolves();
                py::dict d;
                d["solves"] = s.solves;
                d["total_ms"] = s.total_ms;
                d["max_ms"] = s.max_ms;
                return d;
            },
            "What the pose graph's solves took so far on their own thread, off the frame loop, as a dict: solves, "
            "total_ms, max_ms (waits for a solve in progress; no solves without submaps).")
        .def_property_readonly(
            "settings", [](const Pipeline& p) { return p.settings(); },
            "A copy of the settings the pipeline was made with: changing it changes nothing (make a new Pipeline).")
        .def_property_readonly("calib", [](const Pipeline& p) { return p.calib(); })
        .def_property_readonly("frames_processed", &Pipeline::framesProcessed)
        .def(
            "timings",
            [](Pipeline& p) {
                const auto busy = p.claim("timings");
                return timings(p);
            },
            "Per stage: median and mean milliseconds over the frames so far, and the frame count.")
        .def(
            "summary",
            [](Pipeline& p) {
                const auto busy = p.claim("summary");
                return summary(p);
            },
            "The run so far as a dict: device, voxel and index, frames (fused, failed, lost), relocalisation\n"
            "attempts and successes, timings, memory, blocks.")
        .def("__repr__", [](Pipeline& p) {
            const MainEngineSettings& s = p.engine().settings();
            return std::string("<voxfuse.Pipeline ") + toString(s.voxel_type) + " " + toString(s.index_type) + " on " +
                   deviceName(s.device) + ", " + std::to_string(p.framesProcessed()) + " frames>";
        });
}

}  // namespace voxfuse::python
