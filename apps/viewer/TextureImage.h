#pragma once
// An RGBA image held as an OpenGL texture and drawn as a textured quad (legacy OpenGL 2.1, which
// every driver and Mesa's software renderer under Xvfb provide).

#include "PanelLayout.h"
#include "voxfuse/core/Image.h"

namespace voxfuse::viewer {

class TextureImage {
public:
    TextureImage() = default;
    ~TextureImage();
    TextureImage(const TextureImage&) = delete;
    TextureImage& operator=(const TextureImage&) = delete;

    // Copies the image to the texture (an empty image leaves the panel blank). Needs a current GL context.
    void upload(const Image<Vec4u8>& rgba);
    // Draws the image fitted into `cell` (aspect kept). Expects a projection with one unit per pixel
    // and the origin at the top-left.
    void draw(const PanelRect& cell) const;

    int width() const { return width_; }
    int height() const { return height_; }

private:
    unsigned int texture_ = 0;
    int width_ = 0, height_ = 0;
};

}  // namespace voxfuse::viewer
