#pragma once
// One GLFW window with a legacy OpenGL 2.1 context. Every failure (no display, GLFW cannot start, no
// suitable context) throws voxfuse::Error with a message a user can act on.

#include <string>

#include "voxfuse/core/Image.h"

struct GLFWwindow;

namespace voxfuse::viewer {

class GlfwWindow {
public:
    GlfwWindow(int width, int height, const std::string& title);
    ~GlfwWindow();
    GlfwWindow(const GlfwWindow&) = delete;
    GlfwWindow& operator=(const GlfwWindow&) = delete;

    GLFWwindow* handle() const { return window_; }
    bool shouldClose() const;
    void requestClose();
    void setTitle(const std::string& title);
    // Drawable size in pixels (differs from the window size on high-DPI screens).
    void framebufferSize(int& width, int& height) const;
    // Factor from cursor (screen) coordinates to framebuffer pixels.
    double pixelsPerScreenUnit() const;
    // The back buffer as drawn so far, top row first (call before swapBuffers).
    Image<Vec4u8> readBackBuffer() const;
    void swapBuffers();

private:
    GLFWwindow* window_ = nullptr;
};

}  // namespace voxfuse::viewer
