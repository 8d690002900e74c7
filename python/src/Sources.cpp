// voxfuse.open_source, voxfuse.Source and voxfuse.Frame: every recording the CLI reads, its frames as
// NumPy arrays that view the decoded images (no copy; an array keeps its frame alive).

#include <pybind11/stl.h>

#include <cmath>
#include <memory>
#include <mutex>

#include "Bindings.h"
#include "NumpyArrays.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/io/ImageSource.h"
#include "voxfuse/io/LabelledImageSource.h"
#include "voxfuse/io/ThreadedImageSource.h"

namespace voxfuse::python {

namespace {

using FramePtr = std::shared_ptr<RGBDFrame>;

struct Source {
    std::unique_ptr<ImageSource> source;
    bool skip_unreadable = true;
    int unreadable = 0;
    // A source reads from one thread at a time, and the GIL is released while it decodes: a second
    // Python thread iterating the same source is refused (two at once corrupted the frame buffers, or
    // with a reader thread waited forever for an end mark another had taken). Never waits: waiting
    // while holding the GIL could deadlock.
    std::mutex busy;
};

FramePtr nextFrame(Source& s) {
    std::unique_lock<std::mutex> busy(s.busy, std::try_to_lock);
    if (!busy) throw Error("Source: the source is being read by another thread (one thread at a time per source)");
    for (;;) {
        auto frame = std::make_shared<RGBDFrame>();
        try {
            bool more;
            {
                py::gil_scoped_release no_gil;  // decoding is the slow part
                more = s.source->next(*frame);
            }
            if (!more) throw py::stop_iteration();
            return frame;
        } catch (const IoError& e) {
            if (!s.skip_unreadable) throw;
            ++s.unreadable;
            if (PyErr_WarnEx(PyExc_RuntimeWarning, (std::string("skipping unreadable frame: ") + e.what()).c_str(), 1) <
                0)
                throw py::error_already_set();
        }
    }
}

}  // namespace

void bindSources(py::module_& m) {
    py::class_<RGBDFrame, FramePtr>(
        m, "Frame",
        "One frame as read from a source. Its arrays view the decoded images without a copy (writable;\n"
        "np.copy() them to keep them apart from the frame).\n\n"
        "Frame(depth, rgb=None, *, calib, index=0, timestamp=None) makes one from arrays (copied once), for\n"
        "sources written in Python (voxfuse.realsense): depth uint16 raw or float metres, rgb uint8 (H, W, 3|4),\n"
        "both the sizes calib's cameras have; timestamp in seconds (default index / 30).")
        .def(py::init([](const py::handle& depth, const py::object& rgb, const RGBDCalib& calib, int index,
                         const py::object& timestamp) {
                 if (index < 0) throw py::value_error("index must not be negative");
                 auto f = std::make_shared<RGBDFrame>();
                 copyDepth(depth, calib, 0.f, f->depth_raw);
                 if (!rgb.is_none()) copyRgb(rgb, calib, f->rgb);
                 f->index = index;
                 f->timestamp_s = timestamp.is_none() ? double(index) / 30.0 : timestamp.cast<double>();
                 if (!std::isfinite(f->timestamp_s)) throw py::value_error("timestamp must be a finite number");
                 f->depth_path = "frame " + std::to_string(index) + " made from arrays";
                 f->labels_path = f->depth_path;
                 return f;
             }),
             py::arg("depth"), py::arg("rgb") = py::none(), py::kw_only(), py::arg("calib"), py::arg("index") = 0,
             py::arg("timestamp") = py::none())
        .def_readonly("index", &RGBDFrame::index, "0-based position in the source.")
        .def_readonly("timestamp", &RGBDFrame::timestamp_s,
                      "Seconds (the source's clock; index / 30 when it has none).")
        .def_property_readonly(
            "depth",
            [](const FramePtr& f) {
                return viewOf<std::uint16_t>(
                    f, f->depth_raw.host(), {f->depth_raw.height(), f->depth_raw.width()},
                    {py::ssize_t(f->depth_raw.width() * sizeof(std::uint16_t)), py::ssize_t(sizeof(std::uint16_t))});
            },
            "Raw depth, uint16 (H, W); 0 = no measurement; metres = raw * calib.depth_scale.")
        .def_property_readonly(
            "rgb",
            [](const FramePtr& f) -> py::object {
                if (f->rgb.empty()) return py::none();
                const py::ssize_t w = f->rgb.width();
                return viewOf<std::uint8_t>(f, reinterpret_cast<const std::uint8_t*>(f->rgb.host()),
                                            {f->rgb.height(), w, 3}, {w * 4, 4, 1});
            },
            "Colour, uint8 (H, W, 3) RGB (a view of RGBA pixels: strides (4W, 4, 1)); None without colour.")
        .def_property_readonly(
            "labels",
            [](const FramePtr& f) -> py::object {
                if (f->labels.empty()) return py::none();
                const py::ssize_t w = f->labels.width();
                return viewOf<ClassId>(f, f->labels.host(), {f->labels.height(), w},
                                       {py::ssize_t(w * sizeof(ClassId)), py::ssize_t(sizeof(ClassId))});
            },
            "Semantic classes, uint16 (H, W) (65535: none); None when the frame has none.")
        .def_property_readonly(
            "ground_truth_pose",
            [](const FramePtr& f) -> py::object {
                if (!f->has_ground_truth) return py::none();
                return matrixToArray(f->T_world_camera_gt);
            },
            "Ground-truth camera-to-world pose (4, 4), or None.")
        .def_readonly("depth_path", &RGBDFrame::depth_path, "Where the depth came from.")
        .def("__repr__", [](const RGBDFrame& f) {
            return "<voxfuse.Frame " + std::to_string(f.index) + ", " + std::to_string(f.depth_raw.width()) + "x" +
                   std::to_string(f.depth_raw.height()) + (f.rgb.empty() ? "" : ", colour") +
                   (f.labels.empty() ? "" : ", labels") + ">";
        });

    py::class_<Source>(m, "Source",
                       "A recorded sequence or camera; iterate it for its frames (see voxfuse.open_source).")
        .def("__iter__", [](Source& s) -> Source& { return s; })
        .def("__next__", &nextFrame)
        .def("__len__",
             [](const Source& s) {
                 if (s.source->frameCount() < 0)
                     throw py::type_error("this source does not know its length in advance");
                 return s.source->frameCount();
             })
        .def_property_readonly(
            "calib", [](const Source& s) { return s.source->calib(); }, "Its Calibration.")
        .def_property_readonly("description", [](const Source& s) { return s.source->description(); })
        .def_property_readonly(
            "ground_truth", [](const Source& s) { return timedPosesToArrays(s.source->groundTruth()); },
            "(timestamps (N,), camera-to-world poses (N, 4, 4)); empty arrays when the source has none.")
        .def_readonly("unreadable_frames", &Source::unreadable, "Frames skipped because they could not be read.")
        .def("__repr__", [](const Source& s) { return "<voxfuse.Source " + s.source->description() + ">"; });

    m.def(
        "open_source",
        [](const std::string& path, const std::string& calib, const std::string& rgb, const std::string& depth,
           int first_index, int min_confidence, const std::string& labels, bool threaded, bool skip_unreadable) {
            SourceOptions o;
            o.calib_path = calib;
            o.rgb_pattern = rgb;
            o.depth_pattern = depth;
            o.first_index = first_index;
            if (min_confidence < 0 || min_confidence > 2) throw ConfigError("min_confidence must be 0, 1 or 2");
            o.min_depth_confidence = min_confidence;
            auto s = std::make_unique<Source>();
            s->source = openImageSource(path, o);
            if (!labels.empty()) {
                LabelStreamOptions lo;
                lo.path = labels;
                s->source = std::make_unique<LabelledImageSource>(std::move(s->source), lo);
            }
            if (threaded || s->source->isLive())
                s->source = std::make_unique<ThreadedImageSource>(std::move(s->source));
            s->skip_unreadable = skip_unreadable;
            return s;
        },
        py::arg("path"), py::kw_only(), py::arg("calib") = "", py::arg("rgb") = "", py::arg("depth") = "",
        py::arg("first_index") = 0, py::arg("min_confidence") = 1, py::arg("labels") = "", py::arg("threaded") = false,
        py::arg("skip_unreadable") = true,
        "Opens what `voxfuse PATH` opens: a TUM RGB-D folder, a per-frame folder (frame-XXXXXX.depth.png), a Stray\n"
        "Scanner capture, an OpenNI .oni recording, or with rgb= and depth= printf patterns a PPM/PGM sequence.\n"
        "calib: an InfiniTAM calib.txt overriding the source's; labels: a folder or list of class images;\n"
        "threaded: decode ahead on a reader thread (and undistort); skip_unreadable: warn and go on past a frame\n"
        "that cannot be read (else voxfuse.IoError).");
}

}  // namespace voxfuse::python
