#pragma once
// How an engine's device layer gets the frame images and scene it reads on its own device.

#include <string>

#include "voxfuse/core/Error.h"
#include "voxfuse/core/Image.h"
#include "voxfuse/core/MemoryBlock.h"

namespace voxfuse {

// The copy of `image` on `where`: the image's own copy when it is current there (MainEngine uploads a
// frame's images once per frame), else a copy made in `staging` (an engine used on its own). nullptr
// for an empty image.
template <class T>
const T* imageOn(Device where, const Image<T>& image, MemoryBlock<T>& staging) {
    if (image.empty()) return nullptr;
    if (image.memory().isCurrent(where)) return image.memory().data(where);
    if (!image.memory().isCurrent(Device::CPU) && !image.memory().isCurrent(Device::CUDA))
        throw DeviceError("a frame image has no current copy");
    staging.allocate(image.pixelCount(), where == Device::CPU, where == Device::CUDA);
    if (where == Device::CPU)
        image.memory().readRange(Device::CUDA, 0, staging.host(), image.pixelCount());
    else
        staging.writeRange(Device::CUDA, 0, image.host(), image.pixelCount());
    return staging.data(where);
}

// Engines of one device refuse a scene that lives on the other.
template <class TScene>
void requireSceneOn(Device where, const TScene& scene, const char* engine) {
    if (scene.location() != where)
        throw DeviceError(std::string(engine) + " on " + deviceName(where) + " got a scene that lives on " +
                          deviceName(scene.location()) +
                          " (engines and scene must share a device; Scene::copyTo moves a map)");
}

}  // namespace voxfuse
