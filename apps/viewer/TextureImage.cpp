#include "TextureImage.h"

#define GL_SILENCE_DEPRECATION
#include <GLFW/glfw3.h>

namespace voxfuse::viewer {

TextureImage::~TextureImage() {
    if (texture_ != 0) glDeleteTextures(1, &texture_);
}

void TextureImage::upload(const Image<Vec4u8>& rgba) {
    if (rgba.empty()) {
        width_ = height_ = 0;
        return;
    }
    if (texture_ == 0) glGenTextures(1, &texture_);
    glBindTexture(GL_TEXTURE_2D, texture_);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    if (rgba.width() != width_ || rgba.height() != height_) {
        width_ = rgba.width();
        height_ = rgba.height();
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP);
        // Non-power-of-two sizes are core since OpenGL 2.0.
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, width_, height_, 0, GL_RGBA, GL_UNSIGNED_BYTE, rgba.host());
    } else {
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, rgba.host());
    }
    glBindTexture(GL_TEXTURE_2D, 0);
}

void TextureImage::draw(const PanelRect& cell) const {
    if (texture_ == 0 || width_ == 0) return;
    const PanelRect r = fitAspect(cell, width_, height_);
    glEnable(GL_TEXTURE_2D);
    glBindTexture(GL_TEXTURE_2D, texture_);
    glColor3f(1.f, 1.f, 1.f);
    // Image row 0 is the top row, and so is y = 0 of the projection: texture coordinates map directly.
    glBegin(GL_QUADS);
    glTexCoord2f(0.f, 0.f);
    glVertex2i(r.x, r.y);
    glTexCoord2f(1.f, 0.f);
    glVertex2i(r.x + r.width, r.y);
    glTexCoord2f(1.f, 1.f);
    glVertex2i(r.x + r.width, r.y + r.height);
    glTexCoord2f(0.f, 1.f);
    glVertex2i(r.x, r.y + r.height);
    glEnd();
    glBindTexture(GL_TEXTURE_2D, 0);
    glDisable(GL_TEXTURE_2D);
}

}  // namespace voxfuse::viewer
