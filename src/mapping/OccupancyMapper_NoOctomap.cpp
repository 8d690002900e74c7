// OccupancyMapper in a build without OctoMap: the API links, construction says what to install.

#include "voxfuse/core/Error.h"
#include "voxfuse/mapping/OccupancyMapper.h"

namespace voxfuse {

struct OccupancyMapper::Impl {
    OccupancySettings settings;
    OccupancyStats stats;
};

OccupancyMapper::OccupancyMapper(const OccupancySettings&) {
    throw ConfigError("this VoxFuse build has no OctoMap support (install liboctomap-dev)");
}
OccupancyMapper::~OccupancyMapper() = default;

// Unreachable: no object can be constructed.
bool OccupancyMapper::submit(const Image<float>&, const Intrinsics&, const Mat4f&) { return false; }
void OccupancyMapper::finish() {}
void OccupancyMapper::write(const std::string&) {}
Occupancy OccupancyMapper::occupancyAt(Vec3f) const { return Occupancy::Unknown; }
OccupancyStats OccupancyMapper::stats() const { return impl_->stats; }
const OccupancySettings& OccupancyMapper::settings() const { return impl_->settings; }

}  // namespace voxfuse
