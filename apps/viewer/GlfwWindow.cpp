#include "GlfwWindow.h"

#include <cstdlib>
#include <cstring>

#define GL_SILENCE_DEPRECATION
#include <GLFW/glfw3.h>

#include "voxfuse/core/Error.h"

namespace voxfuse::viewer {
namespace {

// GLFW reports failures through a callback; keep the last one so the exception can say why.
std::string g_last_glfw_error;

void rememberGlfwError(int code, const char* description) {
    g_last_glfw_error =
        std::string(description ? description : "unknown error") + " (GLFW error " + std::to_string(code) + ")";
}

std::string lastGlfwError() { return g_last_glfw_error.empty() ? std::string("no reason given") : g_last_glfw_error; }

bool haveDisplay() {
#if defined(__linux__) || defined(__FreeBSD__)
    const char* x11 = std::getenv("DISPLAY");
    const char* wayland = std::getenv("WAYLAND_DISPLAY");
    return (x11 && *x11) || (wayland && *wayland);
#else
    return true;  // macOS and Windows always have a desktop to open windows on
#endif
}

}  // namespace

GlfwWindow::GlfwWindow(int width, int height, const std::string& title) {
    // Checked first: without a display glfwInit fails with a message that does not say what to do.
    if (!haveDisplay()) throw Error("cannot open a window: no display (set DISPLAY or use xvfb-run)");
    glfwSetErrorCallback(rememberGlfwError);
    if (!glfwInit()) throw Error("cannot open a window: GLFW failed to start: " + lastGlfwError());
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 2);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 1);
    glfwWindowHint(GLFW_DOUBLEBUFFER, GLFW_TRUE);
    window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
    if (!window_) {
        const std::string why = lastGlfwError();
        glfwTerminate();
        throw Error("cannot open a " + std::to_string(width) + "x" + std::to_string(height) +
                    " window with OpenGL 2.1: " + why);
    }
    glfwMakeContextCurrent(window_);
    glfwSwapInterval(0);  // the frame loop, not the monitor, sets the pace
}

GlfwWindow::~GlfwWindow() {
    glfwDestroyWindow(window_);
    glfwTerminate();
}

bool GlfwWindow::shouldClose() const { return glfwWindowShouldClose(window_) != 0; }

void GlfwWindow::requestClose() { glfwSetWindowShouldClose(window_, GLFW_TRUE); }

void GlfwWindow::setTitle(const std::string& title) { glfwSetWindowTitle(window_, title.c_str()); }

void GlfwWindow::framebufferSize(int& width, int& height) const { glfwGetFramebufferSize(window_, &width, &height); }

double GlfwWindow::pixelsPerScreenUnit() const {
    int fb_width = 0, fb_height = 0, width = 0, height = 0;
    glfwGetFramebufferSize(window_, &fb_width, &fb_height);
    glfwGetWindowSize(window_, &width, &height);
    return width > 0 ? double(fb_width) / width : 1.0;
}

Image<Vec4u8> GlfwWindow::readBackBuffer() const {
    int width = 0, height = 0;
    framebufferSize(width, height);
    if (width <= 0 || height <= 0) throw Error("cannot read the window: its framebuffer is empty (minimised?)");
    Image<Vec4u8> bottom_up({width, height});
    glReadBuffer(GL_BACK);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, bottom_up.host());
    if (const GLenum status = glGetError(); status != GL_NO_ERROR)
        throw Error("cannot read the window: glReadPixels failed with OpenGL error " + std::to_string(status));
    // OpenGL's row 0 is the bottom one; images start at the top.
    Image<Vec4u8> image({width, height});
    for (int y = 0; y < height; ++y)
        std::memcpy(&image.at(0, y), &bottom_up.at(0, height - 1 - y), sizeof(Vec4u8) * std::size_t(width));
    for (std::size_t i = 0; i < image.pixelCount(); ++i) image.host()[i].w = 255;
    return image;
}

void GlfwWindow::swapBuffers() { glfwSwapBuffers(window_); }

}  // namespace voxfuse::viewer
