#include "ViewerApp.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>

#define GL_SILENCE_DEPRECATION
#include <GLFW/glfw3.h>

#include "Hud.h"
#include "voxfuse/core/Timer.h"
#include "voxfuse/io/ImageIO.h"
#include "voxfuse/io/MeshIO.h"
#include "voxfuse/io/ThreadedImageSource.h"
#include "voxfuse/shared/Render.h"

namespace voxfuse::viewer {
namespace {

constexpr float kBackgroundGrey =
    0.15f;  // window behind the panels: tells the panels' edges from black model background

constexpr const char* kWaitingMessage = "waiting for frames from the source";

constexpr const char* kKeysLine =
    "n next | space run | 1-5 mode | drag/wheel view | c camera | m mesh | s map | p shot | r reset | q quit";

const char* modeName(RenderMode mode) {
    switch (mode) {
        case RenderMode::Shaded:
            return "shaded";
        case RenderMode::Color:
            return "colour";
        case RenderMode::Normals:
            return "normals";
        case RenderMode::Depth:
            return "depth";
        case RenderMode::Class:
            return "class";
    }
    return "?";
}

ViewerApp* appOf(GLFWwindow* window) { return static_cast<ViewerApp*>(glfwGetWindowUserPointer(window)); }

// Depth in metres, colour-mapped over the frame's own range so near and far scenes both use the whole map.
void colorMapDepth(const Image<float>& depth_m, Image<Vec4u8>& out) {
    if (out.size() != depth_m.size()) out.resize(depth_m.size());
    float max_m = 0.f;
    for (std::size_t i = 0; i < depth_m.pixelCount(); ++i) max_m = std::max(max_m, depth_m.host()[i]);
    for (std::size_t i = 0; i < depth_m.pixelCount(); ++i)
        out.host()[i] = renderDepth(depth_m.host()[i], max_m > 0.f ? max_m : 1.f);
}

// Where the free view pivots: the mean measured depth, i.e. roughly the middle of what the camera sees.
float meanDepth(const Image<float>& depth_m) {
    double sum = 0.0;
    std::size_t count = 0;
    for (std::size_t i = 0; i < depth_m.pixelCount(); ++i)
        if (depth_m.host()[i] > 0.f) {
            sum += depth_m.host()[i];
            ++count;
        }
    return count > 0 ? float(sum / double(count)) : 1.f;
}

}  // namespace

ViewerApp::ViewerApp(const ViewerOptions& options, std::unique_ptr<ImageSource> source,
                     std::unique_ptr<MainEngine> engine)
    : options_(options),
      source_(std::move(source)),
      read_ahead_(dynamic_cast<ThreadedImageSource*>(source_.get())),
      engine_(std::move(engine)),
      window_(options.window_width, options.window_height, "VoxFuse viewer") {
    record_.source = source_->description();
    record_.settings = engine_->settings();
    record_.tracked = options_.poses == app::PoseSource::Tracker;
    runner_ = std::make_unique<app::SequenceRunner>(*source_, *engine_, options_.poses, record_, "voxfuse_viewer");
    if (options_.skip_frames > 0)
        std::cerr << "voxfuse_viewer: skipped the first " << runner_->skip(options_.skip_frames) << " frames\n";
    running_ = options_.start_running;

    GLFWwindow* w = window_.handle();
    glfwSetWindowUserPointer(w, this);
    glfwSetKeyCallback(
        w, [](GLFWwindow* win, int key, int, int action, int mods) { appOf(win)->onKey(key, action, mods); });
    glfwSetMouseButtonCallback(
        w, [](GLFWwindow* win, int button, int action, int) { appOf(win)->onMouseButton(button, action); });
    glfwSetCursorPosCallback(w, [](GLFWwindow* win, double x, double y) { appOf(win)->onCursor(x, y); });
    glfwSetScrollCallback(w, [](GLFWwindow* win, double, double dy) { appOf(win)->onScroll(dy); });
    updateTitle();
}

ViewerApp::~ViewerApp() { glfwSetWindowUserPointer(window_.handle(), nullptr); }

bool ViewerApp::processingDone() const {
    return end_of_source_ || (options_.max_frames > 0 && int(record_.frames.size()) >= options_.max_frames);
}

int ViewerApp::run() {
    bool screenshot_taken = options_.screenshot_path.empty();
    while (!window_.shouldClose()) {
        if ((running_ || step_requested_) && !processingDone()) {
            // A frame read ahead (a camera's) is waited for a moment only: the window is served
            // meanwhile, also while the camera is silent.
            if (frameArrives()) {
                processNextFrame();
                step_requested_ = false;
            }
        } else {
            step_requested_ = false;
        }
        if (processingDone() && running_) {
            running_ = false;
            updateTitle();
        }
        if (model_dirty_) renderModel();
        drawPanels();
        // The back buffer holds exactly what is about to be shown: read it before the swap.
        if (processingDone() && !screenshot_taken) {
            saveScreenshot(options_.screenshot_path);
            screenshot_taken = true;
        }
        if (screenshot_requested_) {
            screenshot_requested_ = false;
            try {
                saveScreenshot((std::filesystem::path(options_.out_dir) / "screenshot.png").string());
            } catch (const std::exception& e) {
                // Unlike --screenshot (a test's result), a failed p must not end the session.
                status_ = "screenshot NOT saved (see the terminal)";
                std::cerr << "voxfuse_viewer: cannot save the screenshot: " << e.what() << "\n";
                updateTitle();
            }
        }
        if (processingDone() && options_.exit_when_done) break;
        window_.swapBuffers();
        // Idle without spinning when nothing is being processed; keep polling while frames flow (or a
        // step waits for the camera's next frame).
        if (running_ || step_requested_ || model_dirty_ || screenshot_requested_)
            glfwPollEvents();
        else
            glfwWaitEvents();
    }
    return 0;
}

void ViewerApp::saveScreenshot(const std::string& path) {
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    if (!parent.empty()) std::filesystem::create_directories(parent);
    writePNG(path, window_.readBackBuffer());
    status_ = "screenshot saved to " + path;
    std::cerr << "voxfuse_viewer: screenshot saved to " << path << "\n";
    updateTitle();
}

bool ViewerApp::frameArrives() {
    if (!read_ahead_) return true;
    if (read_ahead_->waitForFrame(std::chrono::milliseconds(50))) {
        if (status_.rfind(kWaitingMessage, 0) == 0) status_.clear();
        silence_.reset();
        silent_s_ = 0;
        return true;
    }
    // A silent source (a camera starting, unplugged, or a stalled reader) says so after a second,
    // instead of a window that looks frozen.
    if (!silence_) silence_ = std::make_unique<Timer>();
    const int seconds = int(silence_->elapsedMs() / 1000.0);
    if (seconds >= kSilenceShownS && seconds != silent_s_) {
        status_ = std::string(kWaitingMessage) + " (" + std::to_string(seconds) + " s)";
        updateTitle();
    }
    silent_s_ = seconds;
    return false;
}

void ViewerApp::processNextFrame() {
    const Timer wall;
    const app::SequenceRunner::Step step = runner_->step();
    if (step == app::SequenceRunner::Step::End) {
        end_of_source_ = true;
        status_ = "end of the sequence";
        updateTitle();
        return;
    }
    if (step == app::SequenceRunner::Step::Skipped) {
        // Back to the window's events; the next frame comes on the next pass.
        status_ = "frame skipped: " + std::to_string(record_.frames_unreadable) + " unreadable, " +
                  std::to_string(record_.frames_without_pose) + " without a ground-truth pose so far";
        updateTitle();
        return;
    }
    have_frame_ = true;
    updateLiveImages();
    model_dirty_ = true;
    const double seconds = wall.elapsedMs() / 1000.0;
    smoothed_frame_s_ = smoothed_frame_s_ > 0.0 ? 0.8 * smoothed_frame_s_ + 0.2 * seconds : seconds;
    updateTitle();
}

void ViewerApp::updateLiveImages() {
    const View& view = engine_->view();
    colorMapDepth(view.depth, depth_image_);
    depth_texture_.upload(depth_image_);
    color_texture_.upload(view.rgb);
}

void ViewerApp::renderModel() {
    model_dirty_ = false;
    if (!have_frame_) {
        model_image_ = Image<Vec4u8>();
    } else if (free_view_.active()) {
        engine_->renderFromPose(free_view_.pose(), engine_->view().calib.depth, mode_, model_image_);
        model_pose_ = free_view_.pose();
    } else {
        engine_->renderLast(mode_, model_image_);
        model_pose_ = engine_->trackingState().T_world_camera;
    }
    submap_poses_ = engine_->submapPoses();
    loops_ = submap_poses_.empty() ? std::vector<LoopClosure>() : engine_->loopClosures();
    model_texture_.upload(model_image_);
}

void ViewerApp::drawPanels() {
    int width = 0, height = 0;
    window_.framebufferSize(width, height);
    glViewport(0, 0, width, height);
    glClearColor(kBackgroundGrey, kBackgroundGrey, kBackgroundGrey, 1.f);
    glClear(GL_COLOR_BUFFER_BIT);
    glMatrixMode(GL_PROJECTION);
    glLoadIdentity();
    glOrtho(0.0, width, height, 0.0, -1.0, 1.0);  // one unit per pixel, origin top-left like the images
    glMatrixMode(GL_MODELVIEW);
    glLoadIdentity();
    const PanelLayout layout = layoutPanels(width, height);
    model_texture_.draw(layout.model);
    if (!submap_poses_.empty() && !model_image_.empty())
        drawSubmapOverlay(projectSubmaps(submap_poses_, loops_, model_pose_, engine_->view().calib.depth,
                                         fitAspect(layout.model, model_image_.width(), model_image_.height())));
    depth_texture_.draw(layout.live_depth);
    color_texture_.draw(layout.live_color);
    drawStatusBar(layout.status_bar, statusLine(), kKeysLine);
}

void ViewerApp::onKey(int key, int action, int /*mods*/) {
    if (action != GLFW_PRESS && !(action == GLFW_REPEAT && key == GLFW_KEY_N)) return;
    switch (key) {
        case GLFW_KEY_Q:
        case GLFW_KEY_ESCAPE:
            window_.requestClose();
            break;
        case GLFW_KEY_N:
            step_requested_ = true;
            running_ = false;
            break;
        case GLFW_KEY_SPACE:
            running_ = !running_;
            break;
        case GLFW_KEY_1:
            setMode(RenderMode::Shaded);
            break;
        case GLFW_KEY_2:
            setMode(RenderMode::Color);
            break;
        case GLFW_KEY_3:
            setMode(RenderMode::Normals);
            break;
        case GLFW_KEY_4:
            setMode(RenderMode::Depth);
            break;
        case GLFW_KEY_5:
            setMode(RenderMode::Class);
            break;
        case GLFW_KEY_TAB:
            setMode(RenderMode((int(mode_) + 1) % 5));
            break;
        case GLFW_KEY_C:
            free_view_.stop();
            model_dirty_ = true;
            status_ = "following the camera";
            break;
        case GLFW_KEY_M:
            saveMesh();
            break;
        case GLFW_KEY_S:
            saveMap();
            break;
        case GLFW_KEY_P:
            screenshot_requested_ = true;
            break;
        case GLFW_KEY_R:
            resetMap();
            break;
        default:
            return;
    }
    updateTitle();
}

void ViewerApp::setMode(RenderMode mode) {
    mode_ = mode;
    model_dirty_ = true;
    status_.clear();
}

void ViewerApp::saveMesh() {
    const std::filesystem::path path = std::filesystem::path(options_.out_dir) / "mesh.ply";
    try {
        std::filesystem::create_directories(options_.out_dir);
        Mesh mesh;
        engine_->extractMesh(mesh);
        writeMesh(path.string(), mesh);
        status_ = "mesh saved to " + path.string();
        std::cerr << "voxfuse_viewer: mesh " << mesh.vertices.size() << " vertices, " << mesh.triangles.size()
                  << " triangles -> " << path.string() << "\n";
    } catch (const std::exception& e) {
        // A failed save must not end the session: report it and carry on.
        status_ = "mesh NOT saved (see the terminal)";
        std::cerr << "voxfuse_viewer: cannot save the mesh: " << e.what() << "\n";
    }
}

void ViewerApp::saveMap() {
    const std::filesystem::path path = std::filesystem::path(options_.out_dir) / "map.vfm";
    try {
        std::filesystem::create_directories(options_.out_dir);
        engine_->saveMap(path.string());
        status_ = "map saved to " + path.string();
        std::cerr << "voxfuse_viewer: map -> " << path.string() << " (continue it with --load-map)\n";
    } catch (const std::exception& e) {
        status_ = "map NOT saved (see the terminal)";
        std::cerr << "voxfuse_viewer: cannot save the map: " << e.what() << "\n";
    }
}

void ViewerApp::resetMap() {
    engine_->reset();
    free_view_.stop();
    have_frame_ = false;
    model_dirty_ = true;
    status_ = "map reset";
}

void ViewerApp::startFreeViewIfNeeded() {
    if (free_view_.active() || !have_frame_) return;
    free_view_.startAt(record_.frames.back().result.T_world_camera, meanDepth(engine_->view().depth));
    status_ = "free view (c: back to the camera)";
}

bool ViewerApp::cursorInModelPanel(double x, double y) const {
    int width = 0, height = 0;
    window_.framebufferSize(width, height);
    const double scale = window_.pixelsPerScreenUnit();
    return layoutPanels(width, height).model.contains(x * scale, y * scale);
}

void ViewerApp::onMouseButton(int button, int action) {
    if (button != GLFW_MOUSE_BUTTON_LEFT) return;
    dragging_ = action == GLFW_PRESS && cursorInModelPanel(last_cursor_x_, last_cursor_y_);
}

void ViewerApp::onCursor(double x, double y) {
    if (dragging_ && have_frame_) {
        startFreeViewIfNeeded();
        free_view_.orbit(x - last_cursor_x_, y - last_cursor_y_);
        model_dirty_ = true;
        updateTitle();
    }
    last_cursor_x_ = x;
    last_cursor_y_ = y;
}

void ViewerApp::onScroll(double steps) {
    if (!have_frame_ || !cursorInModelPanel(last_cursor_x_, last_cursor_y_)) return;
    startFreeViewIfNeeded();
    free_view_.zoom(steps);
    model_dirty_ = true;
    updateTitle();
}

std::string ViewerApp::statusLine() const {
    char text[512];
    const int total = source_->frameCount();
    const int done = int(record_.frames.size());
    const double engine_ms = done > 0 ? record_.frames.back().result.total_ms : 0.0;
    const double fps = smoothed_frame_s_ > 0.0 ? 1.0 / smoothed_frame_s_ : 0.0;
    const FrameResult* last = done > 0 ? &record_.frames.back().result : nullptr;
    // "tracking good", "LOST (relocalising)", "relocalised"; and the keyframes relocalisation can use.
    std::string tracking = !last ? "tracking -"
                           : last->status == TrackingStatus::Lost
                               ? std::string("LOST") + (last->relocalisation_tried ? " (relocalising)" : "")
                           : last->status == TrackingStatus::Relocalised
                               ? "relocalised"
                               : std::string("tracking ") + toString(last->quality);
    if (last && engine_->settings().relocalisation.enabled)
        tracking += ", " + std::to_string(last->keyframes) + " keyframes";
    if (!submap_poses_.empty())
        tracking +=
            ", " + std::to_string(submap_poses_.size()) + " submaps, " + std::to_string(loops_.size()) + " loops";
    std::snprintf(text, sizeof text, "frame %d%s%s | %.1f ms/frame | %.1f fps | %s | %s%s | %s%s%s", done,
                  total > 0 ? "/" : "", total > 0 ? std::to_string(total).c_str() : "", engine_ms, fps,
                  tracking.c_str(), modeName(mode_), free_view_.active() ? ", free view" : "",
                  running_ ? "running" : "paused", status_.empty() ? "" : " | ", status_.c_str());
    return text;
}

void ViewerApp::updateTitle() { window_.setTitle("VoxFuse | " + statusLine()); }

}  // namespace voxfuse::viewer
