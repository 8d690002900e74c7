// The per-frame pipeline (MainEngineT) and MainEngine::create. Settings and their checks:
// MainEngineSettings.cpp; stage timing: StageClock.h; voxel type dispatch: VoxelTypeDispatch.h; a frame's
// view: ViewFromFrame.h; tracking, loss and relocalisation: RelocalisingTracking.h; swapping: MapSwapping.h.

#include "voxfuse/engines/MainEngine.h"

#include <cmath>
#include <type_traits>

#include "MainEngineSettings.h"
#include "MapSwapping.h"
#include "RelocalisingTracking.h"
#include "StageClock.h"
#include "SubmapEngine.h"
#include "ViewFromFrame.h"
#include "VoxelTypeDispatch.h"
#include "io/TextParsing.h"
#include "voxfuse/core/Error.h"
#include "voxfuse/core/Timer.h"
#include "voxfuse/engines/AllocationEngine.h"
#include "voxfuse/engines/IntegrationEngine.h"
#include "voxfuse/engines/LowLevelEngine.h"
#include "voxfuse/engines/MeshingEngine.h"
#include "voxfuse/engines/RaycastEngine.h"
#include "voxfuse/objects/GlobalCache.h"
#include "voxfuse/objects/Scene.h"
#include "voxfuse/shared/HashAccess.h"
#include "voxfuse/shared/VoxelAccess.h"

namespace voxfuse {
namespace {

// A pose given from outside must be a camera's (a rotation and a plausible position): a scaled or
// sheared matrix would be fused as if it were one, into an empty or garbled map.
void requireCameraPose(const Mat4f& T_world_camera, const char* call) {
    const std::string problem = text::rigidPoseProblem(T_world_camera.m);
    if (!problem.empty()) throw ConfigError(std::string(call) + ": the given pose is no camera pose: " + problem);
}

template <class TVoxel, class TIndex>
class MainEngineT final : public MainEngine {
    static constexpr bool kHash = std::is_same<TIndex, VoxelBlockHash>::value;

public:
    MainEngineT(const MainEngineSettings& settings, const RGBDCalib& calib, TIndex index)
        : settings_(settings),
          scene_(settings.scene, std::move(index), settings.device),
          relocalising_(settings, calib),
          swapping_(settings),
          clock_(settings.device == Device::CUDA) {
        makeEngines();
        view_.calib = calib;
    }

    // On the GPU only the frame's images go up (raw depth, colour, classes); everything else stays there.
    FrameResult processFrame(const RGBDFrame& frame, const Mat4f* T_world_camera_given) override {
        if (T_world_camera_given) requireCameraPose(*T_world_camera_given, "processFrame");
        FrameResult result;
        const Timer total;
        clock_.start(result);

        ++views_converted_;  // first: from here on view_.depth is no longer the last one's, even if this frame throws
        viewFromFrame(frame, settings_, {tracker_->inputs().far_depth, TVoxel::hasLabel, onGpu()}, *low_level_, view_);
        clock_.stageDone("depth");

        if (T_world_camera_given) {
            tracking_ = TrackingState();
            tracking_.T_world_camera = *T_world_camera_given;
            relocalising_.poseGiven(view_, result);
            clock_.stageDone("track");
        } else {
            if (model_released_) raycastModel(nullptr);  // releaseFrameMemory() took the model
            relocalising_.track(trackingContext(), tracking_, result);
        }
        result.tracking = tracking_;
        result.quality = tracking_.quality;
        result.T_world_camera = tracking_.T_world_camera;
        if (tracking_.quality == TrackingQuality::Failed) {
            // Fusing a frame at a wrong pose would smear the map: keep the map and the model raycast.
            clock_.finish();
            result.total_ms = total.elapsedMs();
            return result;
        }

        allocation_stats_ = allocation_->allocate(scene_, view_, tracking_.T_world_camera);
        clock_.stageDone("allocate");

        swapping_.swapIn(scene_, allocation_stats_, clock_);

        integration_->integrate(scene_, view_, tracking_.T_world_camera);
        result.fused = true;
        map_started_ = true;
        clock_.stageDone("integrate");

        raycastModel(&view_.depth);
        clock_.stageDone("raycast");

        if (!T_world_camera_given) relocalising_.frameFused(trackingContext(), tracking_, result);

        swapping_.swapOut(scene_, allocation_stats_, clock_);

        // Between frames, so that no stage holds voxel pointers.
        if (settings_.remove_empty_blocks_every > 0 && ++frames_fused_ % settings_.remove_empty_blocks_every == 0) {
            allocation_->removeEmptyBlocks(scene_);
            if constexpr (kHash) {
                const AllocationStats frame = allocation_stats_;
                allocation_stats_ = scene_.index().stats();
                allocation_stats_.blocks_swapped_in_this_frame = frame.blocks_swapped_in_this_frame;
                allocation_stats_.blocks_swapped_out_this_frame = frame.blocks_swapped_out_this_frame;
            }
        }
        if constexpr (kHash) {
            allocation_stats_.blocks_allocated = scene_.index().blocksInUse();
            allocation_stats_.blocks_stored = scene_.index().storedBlocks();
        }

        result.allocation = allocation_stats_;
        clock_.finish();
        result.total_ms = total.elapsedMs();
        return result;
    }

    float modelCoverage(const View& view) override {
        if (model_released_) raycastModel(nullptr);
        if (model_.points_world.empty() || view.depth.empty()) return 0.f;
        if (onGpu()) model_.points_world.memory().updateHost();  // view(): its host copy is current
        const int factor = settings_.tracking_raycast_downsample;
        const Vec2i size = model_.points_world.size();
        long long valid = 0, covered = 0;
        for (int v = 0; v < size.y; ++v)
            for (int u = 0; u < size.x; ++u) {
                if (!(view.depth.at(u * factor, v * factor) > 0.f)) continue;
                ++valid;
                covered += model_.points_world.at(u, v).w > 0.f ? 1 : 0;
            }
        return valid > 0 ? float(covered) / float(valid) : 0.f;
    }

    void releaseFrameMemory() override {
        for (Image<float>* image : {&view_.depth, &view_.far_depth}) *image = Image<float>();
        view_.rgb = Image<Vec4u8>();
        view_.labels = Image<ClassId>();
        model_ = RenderState();
        display_ = RenderState();
        free_view_ = RenderState();
        display_version_ = -1;
        model_depth_view_ = -1;
        model_released_ = true;
        makeEngines();  // the engines are stateless but for their buffers: new ones start without
    }

    bool locate(const View& view, TrackingState& found) override {
        return relocalising_.locate({scene_, view, *raycast_, *tracker_, settings_, onGpu()}, found);
    }
    std::vector<Mat4f> keyframePoses() const override { return relocalising_.keyframePoses(); }
    bool locateNear(const View& view, const Mat4f& T_world_prior, TrackingState& found) override {
        requireCameraPose(T_world_prior, "locateNear");
        return relocalising_.locateNear({scene_, view, *raycast_, *tracker_, settings_, onGpu()}, T_world_prior, found);
    }

    const MainEngineSettings& settings() const override { return settings_; }
    // On the GPU the frame's depth and the raycast live there: host copies are made when asked for.
    const View& view() const override {
        if (onGpu()) view_.depth.memory().updateHost();
        return view_;
    }
    const TrackingState& trackingState() const override { return tracking_; }
    const RenderState& renderState() const override {
        RenderState& rs = displayRaycast();
        if (onGpu()) rs.updateHost();
        return rs;
    }

    void renderLast(RenderMode mode, Image<Vec4u8>& image) override {
        raycast_->render(scene_, displayRaycast(), mode, image);
    }

    void renderFromPose(const Mat4f& T_world_camera, const Intrinsics& intrinsics, RenderMode mode,
                        Image<Vec4u8>& image) override {
        requireCameraPose(T_world_camera, "renderFromPose");
        raycast_->raycast(scene_, intrinsics, T_world_camera, free_view_);
        raycast_->render(scene_, free_view_, mode, image);
    }
    void renderFromPose(const Mat4f& T_world_camera, const Intrinsics& intrinsics, RenderMode mode,
                        Image<Vec4u8>& image, Image<float>& depth_m) override {
        renderFromPose(T_world_camera, intrinsics, mode, image);
        if (onGpu()) free_view_.points_world.memory().updateHost();
        const Mat4f T_camera_world = rigidInverse(T_world_camera);
        depth_m.resize(intrinsics.size());
        const Vec4f* points = free_view_.points_world.host();
        for (std::size_t i = 0; i < depth_m.pixelCount(); ++i)
            depth_m.host()[i] = points[i].w > 0.f
                                    ? transformPoint(T_camera_world, Vec3f{points[i].x, points[i].y, points[i].z}).z
                                    : 0.f;
    }

    void saveMap(const std::string& path) override {
        MapFileWriter file(path);
        saveMapInto(file);
        file.commit();
    }
    void saveMapInto(MapFileWriter& file) override {
        MapFileInfo pose;
        pose.T_world_camera = tracking_.T_world_camera;
        pose.has_origin = has_source_origin_;
        pose.T_source_world = T_source_world_;
        pose.camera = view_.calib.depth;
        const MapKeyframes keyframes = relocalising_.savedKeyframes();
        if (onGpu())
            writeMap(file, scene_.copyTo(Device::CPU), pose, swapping_.cache(), &keyframes);
        else
            writeMap(file, scene_, pose, swapping_.cache(), &keyframes);
    }

    MapFileInfo loadMap(const std::string& path) override {
        MapFileReader file(path);
        if (file.holdsSubmaps())
            throw IoError(path, "holds a map of submaps: load it with submaps on (MainEngineSettings::submaps)");
        const MapFileInfo info = loadMapFrom(file);
        file.requireEnd();
        return info;
    }
    MapFileInfo loadMapFrom(MapFileReader& file) override {
        // Read into a new host scene first: a file that fails leaves the engine as it was.
        Scene<TVoxel, TIndex> loaded(settings_.scene, newIndex(), Device::CPU);
        std::unique_ptr<GlobalCache> cache = swapping_.newCache();
        MapKeyframes keyframes;
        const MapFileInfo info = readMap(file, loaded, cache.get(), &keyframes);
        swapping_.setCache(std::move(cache));
        scene_ = onGpu() ? loaded.copyTo(Device::CUDA) : std::move(loaded);
        if constexpr (std::is_same<TIndex, VoxelBlockHash>::value)
            allocation_stats_ = scene_.index().stats();
        else
            allocation_stats_ = AllocationStats();
        frames_fused_ = 0;
        tracker_->reset();
        relocalising_.mapLoaded(keyframes);
        tracking_ = TrackingState();
        tracking_.T_world_camera = info.T_world_camera;
        map_started_ = true;
        has_source_origin_ = info.has_origin;
        T_source_world_ = info.T_source_world;
        raycastModel(nullptr);
        return info;
    }

    void setSourceOrigin(const Mat4f& T_source_world) override {
        T_source_world_ = T_source_world;
        has_source_origin_ = true;
    }
    bool sourceOrigin(Mat4f& T_source_world) const override {
        if (has_source_origin_) T_source_world = T_source_world_;
        return has_source_origin_;
    }

    void reset() override {
        resetScene();
        map_started_ = false;
        tracker_->reset();
        relocalising_.forget();
        tracking_ = TrackingState();
        model_ = RenderState();
        ++model_version_;
        // A new map has a new world: the next ground-truth frame defines it again.
        has_source_origin_ = false;
        T_source_world_ = Mat4f::identity();
    }

    std::size_t sceneBytes() const override {
        if constexpr (std::is_same<TIndex, VoxelBlockHash>::value)
            return scene_.voxels().bytes() + scene_.index().tableBytes();
        return scene_.voxels().bytes();
    }
    AllocationStats allocationStats() const override { return allocation_stats_; }
    const TrackerStats& trackerStats() const override { return tracker_->lastStats(); }
    // On the host: a map on the GPU, or with swapped-out blocks, is copied whole for each call.
    void depthWeightsAt(const std::vector<Vec3f>& points_world, std::vector<float>& weights) override {
        if (onGpu() || swapping_.hasStoredBlocks(scene_))
            depthWeightsIn(swapping_.completeHostCopy(scene_), points_world, weights);
        else
            depthWeightsIn(scene_, points_world, weights);
    }

    // The map is meshed where it lives; a map with swapped-out blocks is meshed on the CPU from a host
    // copy with every block in it (the whole map may not fit the active budget on the device).
    void extractMesh(Mesh& mesh) override {
        if (swapping_.hasStoredBlocks(scene_))
            hostMeshing().extractMesh(swapping_.completeHostCopy(scene_), mesh);
        else
            meshing_->extractMesh(scene_, mesh);
    }
    void extractPointCloud(PointCloud& cloud) override {
        if (swapping_.hasStoredBlocks(scene_))
            hostMeshing().extractPointCloud(swapping_.completeHostCopy(scene_), cloud);
        else
            meshing_->extractPointCloud(scene_, cloud);
    }

private:
    bool onGpu() const { return settings_.device == Device::CUDA; }

    static void depthWeightsIn(const Scene<TVoxel, TIndex>& scene, const std::vector<Vec3f>& points_world,
                               std::vector<float>& weights) {
        const float inv_voxel = 1.f / scene.params().voxel_size_m;
        const TVoxel* voxels = scene.voxels().host();
        const auto index = scene.index().data();
        weights.resize(points_world.size());
        for (std::size_t i = 0; i < points_world.size(); ++i) {
            const Vec3f p = points_world[i] * inv_voxel;
            bool found;
            const TVoxel v = readVoxel(
                voxels, index,
                Vec3i{int(std::floor(p.x + 0.5f)), int(std::floor(p.y + 0.5f)), int(std::floor(p.z + 0.5f))}, found);
            weights[i] = found ? float(v.w_depth) : 0.f;
        }
    }

    // The model the next frame is tracked against: a raycast from the current pose at the tracker's
    // resolution, normals from its points, rays starting near what the frame just fused saw
    // (engines/RaycastEngine.h: each a fraction of the cost). `fused_depth`: that frame's depth, if any.
    void raycastModel(const Image<float>* fused_depth) {
        const int factor = settings_.tracking_raycast_downsample;
        // A tracker may align the next frame's colours to the map's (frame to model, docs/DESIGN_NOTES.md,
        // "rgbd is ren plus colour, aligned to the map's colours").
        const bool with_intensity = TVoxel::hasColor && tracker_->inputs().model_intensity;
        raycast_->raycast(scene_, factor > 1 ? view_.calib.depth.downsampled(factor) : view_.calib.depth,
                          tracking_.T_world_camera, model_, RaycastNormals::FromPoints, fused_depth, with_intensity);
        model_depth_view_ = fused_depth ? views_converted_ : -1;
        ++model_version_;
        model_released_ = false;
    }

    // The model seen from the pose of the last model raycast, at the depth camera's resolution with
    // SDF normals, for renders and renderState(): made when first asked for after each model raycast.
    // While the view still holds the depth that raycast was started from (the frame just fused from
    // this pose), its rays start there too.
    RenderState& displayRaycast() const {
        if (display_version_ != model_version_) {
            const bool hint = model_depth_view_ >= 0 && model_depth_view_ == views_converted_;
            // After releaseFrameMemory() the model is raycast again at the next frame: until then from the last pose.
            const Mat4f& T_world_camera = model_released_ ? tracking_.T_world_camera : model_.T_world_camera;
            raycast_->raycast(scene_, view_.calib.depth, T_world_camera, display_, RaycastNormals::SdfGradient,
                              hint ? &view_.depth : nullptr);
            display_version_ = model_version_;
        }
        return display_;
    }

    // The stage engines on the settings' device (again after releaseFrameMemory()).
    void makeEngines() {
        low_level_ = makeLowLevelEngine(settings_.device);
        allocation_ = makeAllocationEngine<TVoxel, TIndex>(settings_.device);
        integration_ = makeIntegrationEngine<TVoxel, TIndex>(settings_.device);
        raycast_ = makeRaycastEngine<TVoxel, TIndex>(settings_.device);
        tracker_ = makeTracker(settings_.tracker, settings_.device);
        meshing_ = makeMeshingEngine<TVoxel, TIndex>(settings_.device);
        host_meshing_.reset();
    }

    typename RelocalisingTracking<TVoxel, TIndex>::Context trackingContext() {
        return {scene_, view_, model_, *tracker_, *raycast_, *low_level_, settings_, clock_, onGpu(), map_started_};
    }

    MeshingEngine<TVoxel, TIndex>& hostMeshing() {
        if (!onGpu()) return *meshing_;
        if (!host_meshing_) host_meshing_ = makeMeshingEngine<TVoxel, TIndex>(Device::CPU);
        return *host_meshing_;
    }

    TIndex newIndex() const {
        if constexpr (std::is_same<TIndex, VoxelBlockHash>::value)
            return VoxelBlockHash(settings_.hash);
        else
            return PlainVoxelArray(settings_.dense_offset, settings_.dense_size);
    }
    void resetScene() {
        if constexpr (std::is_same<TIndex, VoxelBlockHash>::value)
            scene_.clearVoxelBlocks();
        else
            integration_->resetScene(scene_);
        swapping_.setCache(swapping_.newCache());
        allocation_stats_ = AllocationStats();
        frames_fused_ = 0;
    }

    MainEngineSettings settings_;
    Scene<TVoxel, TIndex> scene_;
    std::unique_ptr<LowLevelEngine> low_level_;
    std::unique_ptr<AllocationEngine<TVoxel, TIndex>> allocation_;
    std::unique_ptr<IntegrationEngine<TVoxel, TIndex>> integration_;
    std::unique_ptr<RaycastEngine<TVoxel, TIndex>> raycast_;
    std::unique_ptr<Tracker> tracker_;
    std::unique_ptr<MeshingEngine<TVoxel, TIndex>> meshing_;
    std::unique_ptr<MeshingEngine<TVoxel, TIndex>> host_meshing_;  // swapped maps on the GPU: meshed from a host copy
    mutable View view_;                                            // mutable: view() brings host copies up to date
    TrackingState tracking_;
    RenderState model_;                       // what the tracker aligns the next frame to (raycastModel)
    mutable RenderState display_;             // renders and renderState() (displayRaycast)
    long long model_version_ = 0;             // model raycasts so far
    long long views_converted_ = 0;           // frames whose depth view_ took so far (source indices may repeat)
    long long model_depth_view_ = -1;         // which of them started the last model raycast's rays; -1: none did
    mutable long long display_version_ = -1;  // the model raycast display_ shows
    RenderState free_view_;
    AllocationStats allocation_stats_;
    int frames_fused_ = 0;
    bool has_source_origin_ = false;
    Mat4f T_source_world_ = Mat4f::identity();
    bool map_started_ = false;     // a frame was fused, or a map loaded
    bool model_released_ = false;  // releaseFrameMemory() took model_: raycast it again before use
    RelocalisingTracking<TVoxel, TIndex> relocalising_;
    MapSwapping<TVoxel, TIndex> swapping_;
    StageClock clock_;
};

template <class TVoxel>
std::unique_ptr<MainEngine> createForVoxel(const MainEngineSettings& s, const RGBDCalib& calib) {
    switch (s.index_type) {
        case IndexType::Dense:
            return std::make_unique<MainEngineT<TVoxel, PlainVoxelArray>>(
                s, calib, PlainVoxelArray(s.dense_offset, s.dense_size));
        case IndexType::Hash:
            return std::make_unique<MainEngineT<TVoxel, VoxelBlockHash>>(s, calib, VoxelBlockHash(s.hash));
    }
    throw ConfigError("unknown index type");
}

}  // namespace

std::unique_ptr<MainEngine> MainEngine::create(const MainEngineSettings& requested, const RGBDCalib& calib) {
    const MainEngineSettings s = checkedMainEngineSettings(requested, calib);
    if (s.submaps.enabled) return makeSubmapEngine(s, calib);
    try {
        return visitVoxelType(s.voxel_type,
                              [&](auto tag) { return createForVoxel<typename decltype(tag)::Voxel>(s, calib); });
    } catch (const std::bad_alloc&) {
        throw ConfigError(indexMemoryNeed(s) + " of memory, more than could be allocated: " + indexRemedy(s));
    } catch (const DeviceError& e) {
        if (s.device != Device::CUDA || std::string(e.what()).find("memory") == std::string::npos) throw;
        throw DeviceError(std::string(e.what()) + " (" + indexMemoryNeed(s) + " of GPU memory: " + indexRemedy(s) +
                          ")");
    }
}

}  // namespace voxfuse
