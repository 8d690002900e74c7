#pragma once
// Owns every object and engine of the pipeline and runs it one frame at a time: depth conversion,
// pose (given or tracked), integration, raycast from the new pose. Voxel and index types are picked at
// run time (create() dispatches to the instantiated pairs).

#include <memory>
#include <string>
#include <vector>

#include "voxfuse/core/DeviceMemory.h"
#include "voxfuse/engines/RaycastEngine.h"
#include "voxfuse/engines/Relocaliser.h"
#include "voxfuse/engines/Tracker.h"
#include "voxfuse/io/MapFile.h"
#include "voxfuse/io/RGBDFrame.h"
#include "voxfuse/mapping/PoseGraph.h"
#include "voxfuse/objects/AllocationStats.h"
#include "voxfuse/objects/Mesh.h"
#include "voxfuse/objects/PointCloud.h"
#include "voxfuse/objects/PlainVoxelArray.h"
#include "voxfuse/objects/VoxelBlockHash.h"
#include "voxfuse/objects/RGBDCalib.h"
#include "voxfuse/objects/RenderState.h"
#include "voxfuse/objects/SceneParams.h"
#include "voxfuse/objects/TrackingState.h"
#include "voxfuse/objects/View.h"
#include "voxfuse/objects/Voxel.h"

namespace voxfuse {

// Swapping of the voxel block hash (engines/SwappingEngine.h). The active voxel array holds at most
// MainEngineSettings::hash.max_block_count blocks (on the GPU with Device::CUDA); the rest of the map
// is stored in host memory, or in `swap_file`.
struct SwapSettings {
    bool enabled = false;
    std::string swap_file;        // "" = the global cache in host memory
    int blocks_per_frame = 4096;  // blocks moved each way per frame at most (the transfer buffers' size)
};

// A map of local submaps (docs/DESIGN_NOTES.md, "Submaps"): each a voxel block hash with its own pose
// in the world, the poses optimised as a pose graph (mapping/PoseGraph.h). Hash index only.
struct SubmapSettings {
    bool enabled = false;
    // A new submap starts once the camera is farther than max_distance_m from the active submap's
    // origin (the position of the camera that started it). Odometry drifts with the path (about 1% of
    // the distance and a degree per metre for frame-to-model RGB-D tracking): 1.5 m keeps a submap's
    // own drift near a centimetre, about two voxels of 5 mm. Turning is no reason: what a camera
    // turning on the spot sees new is fused into the submap it stands in, as a single map would, and a
    // young submap of a few views is what tracking loses itself in.
    float max_distance_m = 1.5f;
    // After a new submap starts, frames are still tracked against the old one while they are fused
    // into both, until the new one's model covers as much of a frame as the old one's tracking
    // explained (its inlier share; a young submap of a few views loses the camera), or for this many
    // frames at most (a second at 30 frames/s bounds the doubled fusion).
    int overlap_frames = 30;
};

// The engine's hash tables: 2^16 buckets to start with (a scene of a few square metres), doubling as the
// map grows up to InfiniTAM's 2^20, each with an excess list of an eighth; the block ceiling is left to
// the engine (kAutomaticBlockCount).
inline VoxelBlockHashSettings engineHashDefaults() {
    VoxelBlockHashSettings s;
    s.bucket_count = 1 << 16;
    s.excess_entry_count = 1 << 13;
    s.max_bucket_count = 1 << 20;
    s.max_block_count = kAutomaticBlockCount;
    return s;
}

struct MainEngineSettings {
    SceneParams scene;
    // Colour voxels: the default tracker (rgbd) aligns each frame's colours to the map's.
    VoxelType voxel_type = VoxelType::SRgb;
    IndexType index_type = IndexType::Hash;
    // Where the frame loop runs and the scene lives. With Device::CUDA only the raw images go up;
    // image processing, tracking, allocation, integration, raycast, renders, meshes and clouds run on
    // the GPU, and host copies (view(), renderState()) are brought up to date when asked for.
    Device device = Device::CPU;
    // Dense index: the box of voxels (grid units; the first camera looks along +z from the origin).
    Vec3i dense_offset{-256, -256, 0};
    Vec3i dense_size{512, 512, 512};
    // Hash index: table sizes and the most voxel blocks it may hold (memory grows on demand up to
    // it). The default ceiling, kAutomaticBlockCount, is chosen by create(): automaticMaxBlockCount().
    VoxelBlockHashSettings hash = engineHashDefaults();
    // Blocks that never received an update go back to the free stack every this many frames (0 = never).
    int remove_empty_blocks_every = 10;
    // How the pose of each frame is estimated when none is given.
    TrackerSettings tracker;
    // The tracker aligns each frame to a raycast of the model from the last pose, made at the depth
    // camera's resolution divided by this (1, 2 or 4). Half resolution tracks as well as full (the
    // finest level's pixels then meet the model pixel their area covers) at a quarter of the rays;
    // renders and renderState() are always raycast at full resolution.
    int tracking_raycast_downsample = 2;
    // A pixel without a depth measurement between two neighbours that agree within this fraction of
    // their depth (left and right, else above and below) takes their mean, for tracking and fusion
    // alike; 0 keeps every gap. See ConvertDepthPixels in shared/LowLevel.h.
    float depth_gap_tolerance = 0.02f;
    // Hash only: only the part of the map near the view stays in the voxel array.
    SwapSettings swap;
    // Keyframes while tracking is good, and finding the camera again from them once it is lost.
    RelocalisationSettings relocalisation;
    SubmapSettings submaps;
};

VoxelType parseVoxelType(
    const std::string& name);  // "s", "f", "s_rgb", "f_rgb", "s_label", "s_rgb_label"; ConfigError otherwise
const char* toString(VoxelType type);
bool voxelTypeHasColor(VoxelType type);
bool voxelTypeHasLabels(VoxelType type);
IndexType parseIndexType(const std::string& name);  // "dense" or "hash"; ConfigError otherwise
const char* toString(IndexType type);

struct StageTime {
    const char* stage;  // "depth", "track", "allocate", "integrate", "raycast", with swapping "swap_in", "swap_out",
                        // and with relocalisation "relocalise" (a lost frame) and "keyframes" (a well-tracked one)
    double ms;          // wall clock; on the GPU up to the end of the stage's queued work
};

// Where the camera stands after a frame.
enum class TrackingStatus {
    Tracking,     // the pose was tracked from the previous one (or given)
    Lost,         // no pose: tracking failed and nothing was found again; the frame was not fused
    Relocalised,  // the first pose after a loss, found by relocalisation
};
const char* toString(TrackingStatus status);  // "tracking", "lost", "relocalised"

struct FrameResult {
    bool fused = false;  // the frame was integrated into the map (not when tracking failed)
    TrackingQuality quality = TrackingQuality::Good;
    TrackingStatus status = TrackingStatus::Tracking;
    bool relocalisation_tried = false;         // the frame was looked up among the keyframes and candidates refined
    int keyframes = 0;                         // in the relocaliser's database after this frame
    Mat4f T_world_camera = Mat4f::identity();  // when lost: the last good pose
    // The tracker's full verdict (inlier ratio, residual, condition), also when the engine found it
    // implausible; on a relocalised frame the accepted candidate's; zero on a frame only relocalisation saw.
    TrackingState tracking;
    double total_ms = 0.0;  // the engine's processing of this frame (no file decoding)
    std::vector<StageTime> stages;
    AllocationStats allocation;  // the index after this frame (all zero for the dense index)
};

// The block ceiling of a hash map whose settings ask for kAutomaticBlockCount. A fixed 2^18 blocks
// (InfiniTAM's size; 1 GiB of s_rgb voxels) ran out on long or large scans while most of a machine's
// memory lay unused, and a map that cannot grow loses what the camera sees next, and then the camera.
// As many blocks as the table has entries (each block needs one), at most 2^22, and no more than
// three quarters of `available_bytes` (the free memory of the device the map lives on when the engine
// is made: MemAvailable on the CPU, cudaMemGetInfo on the GPU) holds beside the tables, in steps of
// 2^16 blocks; 2^18 when the free memory is unknown (0). The array still grows only with the scene.
// On the GPU a growth reallocates the array and copies it, so both copies must fit at once: there
// each block counts twice.
int automaticMaxBlockCount(Device device, std::size_t voxel_bytes, const VoxelBlockHashSettings& hash,
                           double available_bytes);

// A revisit found by loop closure between submaps: at the engine's `frame`th processed frame (from 0)
// the camera, tracked in submap `to_submap`, was found in the older submap `from_submap`.
struct LoopClosure {
    int frame = 0;
    int from_submap = 0;
    int to_submap = 0;
    float residual_m = 0.f;  // the accepted pose's tracking residual and inlier ratio in the older submap
    float inlier_ratio = 0.f;
    double chi2 = 0.0;      // its edge's squared Mahalanobis residual at the pose graph's last solution
    bool rejected = false;  // dropped by the pose graph as an outlier
};

// A submap as the map places it now.
struct SubmapPose {
    Mat4f T_world_submap = Mat4f::identity();  // the pose graph's last solution the map adopted
    int parent = -1;  // the submap it started from, joined to it by an odometry edge; -1: the first
};

class MainEngine {
public:
    // settings() then holds the settings as used: an automatic block ceiling is replaced by its value.
    static std::unique_ptr<MainEngine> create(const MainEngineSettings& settings, const RGBDCalib& calib);
    virtual ~MainEngine() = default;

    // Processes one frame. With `T_world_camera_given` (e.g. ground truth) that pose is used; without
    // it the tracker estimates the pose against the model (the first frame defines the world). A frame
    // whose tracking failed is not fused: the map and the last good pose stay as they were. Tracking
    // is then lost, and with MainEngineSettings::relocalisation each frame is looked up among the
    // keyframes until a candidate pose passes its strict test; nothing is fused until then.
    virtual FrameResult processFrame(const RGBDFrame& frame, const Mat4f* T_world_camera_given) = 0;

    virtual const MainEngineSettings& settings() const = 0;
    virtual const View& view() const = 0;
    virtual const TrackingState& trackingState() const = 0;
    // The model raycast from the pose of the last processed frame (the last good pose after a failure),
    // at the depth camera's resolution: points and SDF normals in world coordinates. Made when first
    // asked for after a frame (the tracker's own raycast may be coarser).
    virtual const RenderState& renderState() const = 0;
    // Renders the model from that pose (renderState()).
    virtual void renderLast(RenderMode mode, Image<Vec4u8>& image) = 0;
    // Raycasts and renders the model from any viewpoint (does not disturb the tracking raycast).
    virtual void renderFromPose(const Mat4f& T_world_camera, const Intrinsics& intrinsics, RenderMode mode,
                                Image<Vec4u8>& image) = 0;
    // The same, with each pixel's depth along the camera's optical axis in `depth_m` (metres; 0 where
    // the ray met no surface): renders of several maps are composited by it.
    virtual void renderFromPose(const Mat4f& T_world_camera, const Intrinsics& intrinsics, RenderMode mode,
                                Image<Vec4u8>& image, Image<float>& depth_m) = 0;
    // Clears the map, the pose, the keyframes and the source origin (the next map's world is defined
    // anew, by its first frame).
    virtual void reset() = 0;
    // Bytes held by the voxel storage and the index's tables.
    virtual std::size_t sceneBytes() const = 0;
    // The index after the last frame (all zero for the dense index).
    virtual AllocationStats allocationStats() const = 0;
    // What the tracker did on the last frame (per-level timings and iterations).
    virtual const TrackerStats& trackerStats() const = 0;
    // The map's surface by marching cubes (engines/MeshingEngine.h), with colours for colour voxels.
    virtual void extractMesh(Mesh& mesh) = 0;
    // The mesh's vertices only (one point per zero-crossing voxel edge): cheaper than extractMesh.
    virtual void extractPointCloud(PointCloud& cloud) = 0;

    // Writes the map to a map file (io/MapFile.h) with the current pose, where tracking resumes, and the
    // keyframes, by which a later run relocalises in it. With submaps, a map of submaps
    // (io/SubmapMapFile.h). IoError naming the file on failure; a failed save leaves no half-written
    // file.
    virtual void saveMap(const std::string& path) = 0;
    // Replaces the map with a map file's and resumes from the pose it was saved with: the model is
    // raycast from there. The next frame is looked up as a lost frame is (engines/Relocaliser.h): from
    // that pose first, then from the saved keyframes, and only a pose that passes relocalisation's
    // check is fused, so a new recording of the same place may start anywhere in the map. (Without
    // relocalisation it is tracked from the saved pose.) The file must match this engine's voxel type,
    // index settings, voxel size and mu (settingsForMap() makes settings that do); IoError naming the
    // file and the mismatch otherwise. With submaps it loads a map of submaps, or a single map as the
    // first submap. With swapping every block of the map starts stored in the global cache. A file
    // that fails leaves the engine as it was. Returns the file's header (for a map of submaps, the
    // map's as a whole).
    virtual MapFileInfo loadMap(const std::string& path) = 0;
    // The same for one map among others in a file (a map of submaps holds one per submap): the map is
    // written into / read from where the file stands. A map of submaps refuses them (ConfigError):
    // it is a file of its own.
    virtual void saveMapInto(MapFileWriter& file) = 0;
    virtual MapFileInfo loadMapFrom(MapFileReader& file) = 0;
    // With poses from a source's ground truth: the world frame's pose in the source's frame (its first
    // frame, or what a loaded map says). SequenceRunner sets it; saveMap() stores it. False if unknown.
    virtual void setSourceOrigin(const Mat4f& T_source_world) = 0;
    virtual bool sourceOrigin(Mat4f& T_source_world) const = 0;

    // With submaps: the pose of every frame processed since the map began that has one (in order; lost
    // frames have none, as in a trajectory), from the submaps' poses as the pose graph last optimised
    // them (waits for a solve in progress). Without submaps the poses as tracked are final: returns false.
    virtual bool optimisedPoses(std::vector<Mat4f>& /*T_world_camera*/) { return false; }
    // The submaps the map holds (1 without submaps).
    virtual int submapCount() const { return 1; }
    // Every submap's pose now (what tracking and renders use; no wait for a solve in progress). Empty
    // without submaps.
    virtual std::vector<SubmapPose> submapPoses() const { return {}; }
    // Loop closure between submaps: the pose in this map of the frame in `view` (converted by an engine
    // of the same settings), found from the keyframes most like it and checked as relocalisation checks
    // its candidates (engines/Relocaliser.h); nothing is fused and the engine's pose stays. Returns
    // whether one passed, with the tracker's verdict and pose (this map's world) in `found`. False
    // without relocalisation (it keeps the keyframes).
    virtual bool locate(const View& /*view*/, TrackingState& /*found*/) { return false; }
    // The keyframes' poses (this map's world), oldest first; empty without relocalisation.
    virtual std::vector<Mat4f> keyframePoses() const = 0;
    // Another map of the same place, made separately (a map file of this map's voxel type, voxel
    // size and mu: a map of submaps or a single map), joined to this one as submaps of it. Both maps
    // are rendered from their submaps' first cameras and keyframe poses; each view of the other map is
    // aligned to this one from the poses of the views here most like it (fern codes) and checked as
    // relocalisation checks a candidate (locateNear). Each of its submaps with a view found joins the
    // submap it was found in by a loop edge, and the pose graph places the other map's submaps with
    // their own edges. Returns the joins found (frame -1; from_submap this map's,
    // to_submap the other's as numbered here now). IoError for a file that does not fit; Error when
    // no view of it is found here (this map is unchanged then). Needs submaps (ConfigError without).
    virtual std::vector<LoopClosure> mergeMap(const std::string& path) {
        throw ConfigError(path + ": merging maps needs submaps (MainEngineSettings::submaps)");
    }
    // The same from a pose the frame is believed to be near (this map's world), without keyframes: the
    // frame is aligned to the model raycast from `T_world_prior` and accepted as a relocalisation
    // candidate is. For revisits seen from another angle, which keyframes do not recognise.
    virtual bool locateNear(const View& /*view*/, const Mat4f& /*T_world_prior*/, TrackingState& /*found*/) {
        return false;
    }
    // How much of a frame the map would explain: the share of `view`'s depth pixels (converted by an
    // engine of the same settings; sampled at the tracking raycast's resolution) where the model this
    // engine would track the next frame against (its raycast from the last pose) has a surface.
    virtual float modelCoverage(const View& view) = 0;
    // The depth weight of the voxel nearest to each point (this map's world frame, metres; 0 where
    // nothing was observed), into `weights`. Submaps keep each part of the surface from the submap that
    // observed it most (SubmapEngine's meshes and clouds). Reads a host copy of a map on the GPU.
    virtual void depthWeightsAt(const std::vector<Vec3f>& points_world, std::vector<float>& weights) = 0;
    // With submaps: every loop closure found so far, with the pose graph's verdict (waits for a solve in
    // progress). Empty without submaps.
    virtual std::vector<LoopClosure> loopClosures() { return {}; }
    // With submaps: what the pose graph's solves took so far, off the frame loop (waits for a solve in
    // progress). No solves without submaps.
    virtual PoseGraphSolveStats poseGraphSolves() { return {}; }
    // Frees what the frame loop keeps between frames: the view's images, the model raycast and renders,
    // and the engines' per-frame buffers (the tracker's pyramids among them, tens of MB at VGA). The
    // map, the keyframes and the pose stay. Submaps release the ones they are not tracking against.
    // The buffers come back with the next frame, and tracking resumes as after a tracker reset: the
    // next tracked frame is aligned to the model raycast again from the last pose, with no motion
    // predicted from before the release.
    virtual void releaseFrameMemory() = 0;
};

// `base` with the voxel type, index, index settings, voxel size and mu of a map file, so that an engine
// created with them can load it, and submaps on for a map of submaps (a single map loads with them on
// or off); every other setting stays as in `base`, the hash table's growth (max_bucket_count) too.
MainEngineSettings settingsForMap(const MapFileInfo& info, MainEngineSettings base);

}  // namespace voxfuse
