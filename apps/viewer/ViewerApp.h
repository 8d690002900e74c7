#pragma once
// The interactive viewer: InfiniTAM's UI on a MainEngine. A large panel shows the model raycast from
// the tracked camera (or from the free view), two small ones the live depth and colour; the title
// and status bars show the frame, per-frame time and fps. Frames come through app::SequenceRunner, the loop
// every front-end shares.

#include <memory>
#include <string>

#include "GlfwWindow.h"
#include "OrbitCamera.h"
#include "RunRecord.h"
#include "SequenceRunner.h"
#include "SubmapOverlay.h"
#include "TextureImage.h"
#include "voxfuse/core/Timer.h"
#include "voxfuse/engines/MainEngine.h"
#include "voxfuse/io/ImageSource.h"

namespace voxfuse {
class ThreadedImageSource;
}

namespace voxfuse::viewer {

struct ViewerOptions {
    int window_width = 1200;              // 2/3 for the model, 1/3 for the live images, a 40-pixel status bar:
    int window_height = 640;              // 4:3 panels at this size
    int max_frames = 0;                   // stop processing after N frames (0 = the whole source)
    int skip_frames = 0;                  // dropped from the start of the source first
    bool start_running = true;            // process continuously from the start (space toggles)
    std::string screenshot_path;          // save the window as PNG once processing stops
    bool exit_when_done = false;          // quit once processing stops (after the screenshot)
    std::string out_dir = "voxfuse_out";  // where m writes mesh.ply, s map.vfm and p screenshot.png
    app::PoseSource poses = app::PoseSource::Tracker;
};

class ViewerApp {
public:
    ViewerApp(const ViewerOptions& options, std::unique_ptr<ImageSource> source, std::unique_ptr<MainEngine> engine);
    ~ViewerApp();
    // Runs until the window closes (q, Esc) or, with exit_when_done, until processing stops. Returns
    // the process exit status.
    int run();

    // Input, forwarded from GLFW's callbacks.
    void onKey(int key, int action, int mods);
    void onMouseButton(int button, int action);
    void onCursor(double x, double y);
    void onScroll(double steps);

private:
    bool processingDone() const;
    bool frameArrives();  // the next frame can be taken without holding the window up (see run())
    void processNextFrame();
    void updateLiveImages();
    void renderModel();
    void drawPanels();
    void saveMesh();
    void saveMap();
    void saveScreenshot(const std::string& path);
    void resetMap();
    void setMode(RenderMode mode);
    void startFreeViewIfNeeded();
    bool cursorInModelPanel(double x, double y) const;
    std::string statusLine() const;  // frame, times, tracking, mode: the title bar and the status bar show it
    void updateTitle();

    ViewerOptions options_;
    std::unique_ptr<ImageSource> source_;
    ThreadedImageSource*
        read_ahead_;  // source_, when frames are read ahead (a camera's): waited for a moment at a time
    std::unique_ptr<MainEngine> engine_;
    app::RunRecord record_;
    std::unique_ptr<app::SequenceRunner> runner_;
    GlfwWindow window_;

    TextureImage model_texture_, depth_texture_, color_texture_;
    Image<Vec4u8> model_image_, depth_image_;
    // With submaps: where they were when the model panel was last rendered, and its camera, for the
    // overlay of submaps and loops (SubmapOverlay.h).
    std::vector<SubmapPose> submap_poses_;
    std::vector<LoopClosure> loops_;
    Mat4f model_pose_ = Mat4f::identity();
    RenderMode mode_ = RenderMode::Shaded;
    OrbitCamera free_view_;
    bool have_frame_ = false;            // a frame was processed since start or reset: there is a model to show
    bool model_dirty_ = false;           // the model panel must be rendered again
    bool running_ = true;                // continuous processing
    bool step_requested_ = false;        // n was pressed
    bool screenshot_requested_ = false;  // p was pressed
    bool end_of_source_ = false;
    bool dragging_ = false;
    double last_cursor_x_ = 0.0, last_cursor_y_ = 0.0;
    double smoothed_frame_s_ = 0.0;           // wall time per frame (reading, processing, display), smoothed
    std::string status_;                      // last action, e.g. "mesh saved to voxfuse_out/mesh.ply"
    static constexpr int kSilenceShownS = 1;  // a source silent this long is shown as waited for
    std::unique_ptr<Timer> silence_;          // since the source last had a frame ready, while it has none
    int silent_s_ = 0;                        // whole seconds of that silence shown
};

}  // namespace voxfuse::viewer
