// SubmapEngine: frames are tracked against the active submap and fused into it; when the camera has
// left the active submap's neighbourhood (SubmapSettings::max_distance_m) a new submap starts at the camera, and for
// SubmapSettings::overlap_frames frames each frame is still tracked against the old submap and fused
// into both, after which the new one is tracked against. Each submap is a MainEngine whose world is the
// submap's frame: the camera that started it. Consecutive submaps are joined by odometry edges.

#include "SubmapEngine.h"

#include "SubmapEdges.h"

#include <algorithm>
#include <set>
#include <utility>
#include <cmath>
#include <string>
#include <vector>

#include "voxfuse/core/Error.h"
#include "voxfuse/core/Timer.h"
#include "voxfuse/engines/FernEncoder.h"
#include "voxfuse/io/SubmapMapFile.h"
#include "voxfuse/mapping/PoseGraph.h"

namespace voxfuse {
namespace {

// Older submaps a novel frame is looked up in, nearest first: each costs a keyframe lookup and the
// refinement of its candidates.
constexpr int kLoopSubmapsPerFrame = 2;
// A submap is searched only where the camera is within this share of its neighbourhood (the distance
// that starts a new submap): a quarter of it is hysteresis.
constexpr float kLoopSearchShare = 0.75f;

// Merging maps: each submap is seen from its first camera and at most this many keyframes' poses less
// one, spread over them (here: the views the other map's are compared with; there: the other map's,
// tried until one of a submap's is found). The rendered depth is stored in steps of 0.1 mm (a TUM
// PNG's are 0.2 mm).
constexpr int kMergeViewsHere = 16;
constexpr int kMergeViewsThere = 8;
constexpr float kRenderedDepthStepM = 0.0001f;

constexpr int kMinSubmapBuckets = 4096;
constexpr int kMinSubmapExcess = 1024;

using submap_edges::distanceM;  // of a camera or submap from the origin of the frame it is given in

// Up to `count` of `poses`, spread evenly from the first to the last.
std::vector<Mat4f> spread(const std::vector<Mat4f>& poses, int count) {
    if (int(poses.size()) <= count) return poses;
    if (count < 2) return {poses.begin(), poses.begin() + std::max(0, count)};
    std::vector<Mat4f> some;
    for (int i = 0; i < count; ++i) some.push_back(poses[std::size_t(i) * (poses.size() - 1) / std::size_t(count - 1)]);
    return some;
}

// What a depth camera of `calib` at T_map_camera would record of `map` (its surface raycast: depth and,
// with `color`, the fused colours), as a frame.
RGBDFrame renderedFrame(MainEngine& map, const Mat4f& T_map_camera, const RGBDCalib& calib, bool color) {
    Image<Vec4u8> image;
    Image<float> depth_m;
    map.renderFromPose(T_map_camera, calib.depth, RenderMode::Color, image, depth_m);
    RGBDFrame frame;
    frame.index = 0;
    frame.depth_raw.resize(depth_m.size());
    for (std::size_t i = 0; i < depth_m.pixelCount(); ++i) {
        const float raw = std::round(depth_m.host()[i] / calib.disparity.a);
        frame.depth_raw.host()[i] = raw > 0.f && raw < 65535.f ? std::uint16_t(raw) : 0;
    }
    if (color) frame.rgb = std::move(image);
    return frame;
}

void toWorld(const Mat4f& T_world_submap, TrackingState& t) { t.T_world_camera = T_world_submap * t.T_world_camera; }
void toWorld(const Mat4f& T_world_submap, FrameResult& r) {
    r.T_world_camera = T_world_submap * r.T_world_camera;
    toWorld(T_world_submap, r.tracking);
}

class SubmapEngine final : public MainEngine {
public:
    SubmapEngine(const MainEngineSettings& settings, const RGBDCalib& calib)
        : calib_(calib), submap_settings_(settings.submaps) {
        local_settings_ = settings;
        local_settings_.submaps.enabled = false;
        // A submap holds the part of the scene seen from its stretch of the path: its tables start at an
        // eighth of the map's (and grow as the map's do), so that many submaps cost what one map does.
        local_settings_.hash.bucket_count = std::max(kMinSubmapBuckets, settings.hash.bucket_count / 8);
        local_settings_.hash.excess_entry_count = std::max(kMinSubmapExcess, settings.hash.excess_entry_count / 8);
        // Most submaps stay small: their voxel arrays grow in steps of a quarter of the map's.
        local_settings_.hash.blocks_per_growth = std::max(1, settings.hash.blocks_per_growth / 4);
        startMap();
        // The block ceiling as the first submap's engine chose it serves every submap.
        local_settings_ = submaps_[0].engine->settings();
        settings_ = settings;
        settings_.hash.max_block_count = local_settings_.hash.max_block_count;
    }

    FrameResult processFrame(const RGBDFrame& frame, const Mat4f* T_world_camera_given) override {
        const Timer total;
        adoptSolution();
        Submap& active = submaps_[active_];
        Mat4f T_submap_given;
        if (T_world_camera_given) T_submap_given = rigidInverse(active.T_world_submap) * *T_world_camera_given;
        FrameResult result = active.engine->processFrame(frame, T_world_camera_given ? &T_submap_given : nullptr);
        const Mat4f T_submap_camera = result.T_world_camera;
        toWorld(active.T_world_submap, result);
        ++frames_processed_;
        last_T_world_camera_ = result.T_world_camera;

        if (result.status == TrackingStatus::Lost && !T_world_camera_given) {
            const Timer search;
            relocaliseInOtherSubmaps(frame, result);
            result.stages.push_back({"submap_relocalise", search.elapsedMs()});
            result.total_ms = total.elapsedMs();
            return result;
        }
        placing_ = false;
        frame_poses_.push_back({active_, T_submap_camera});
        // A frame the active submap took as a keyframe shows what it had not seen: perhaps a place an
        // older submap has.
        const bool novel = active.keyframes >= 0 && result.keyframes > active.keyframes;
        active.keyframes = result.keyframes;
        if (result.fused && novel && !T_world_camera_given) {
            const Timer search;
            const bool closed = searchLoop(frame, T_submap_camera);
            result.stages.push_back({"loop_search", search.elapsedMs()});
            if (closed) {
                result.total_ms = total.elapsedMs();
                return result;
            }
        }
        if (result.fused) {
            if (building_ >= 0) {
                const Timer fuse;
                Submap& building = submaps_[building_];
                // The new submap is tracked against once its model explains as much of the frame as the
                // old one did (the tracker's inlier share; given poses have none), or after
                // overlap_frames at most.
                const float coverage =
                    T_world_camera_given ? 0.f : building.engine->modelCoverage(active.engine->view());
                const Mat4f T_building_camera = rigidInverse(building.T_world_submap) * result.T_world_camera;
                building.engine->processFrame(frame, &T_building_camera);
                result.stages.push_back({"submap_fuse", fuse.elapsedMs()});
                if (--overlap_left_ <= 0 || (!T_world_camera_given && coverage >= result.tracking.inlier_ratio))
                    switchTo(building_);
            } else if (distanceM(T_submap_camera) > submap_settings_.max_distance_m) {
                const Timer start;
                startSubmap(frame, result.T_world_camera, T_submap_camera);
                result.stages.push_back({"submap_start", start.elapsedMs()});
            }
        }
        result.total_ms = total.elapsedMs();
        return result;
    }

    const MainEngineSettings& settings() const override { return settings_; }
    const View& view() const override { return submaps_[active_].engine->view(); }
    const TrackingState& trackingState() const override {
        tracking_ = submaps_[active_].engine->trackingState();
        tracking_.T_world_camera = last_T_world_camera_;
        return tracking_;
    }
    // The active submap's raycast, in world coordinates.
    const RenderState& renderState() const override {
        if (world_render_version_ == frames_processed_) return world_render_;
        const Submap& active = submaps_[active_];
        const RenderState& local = active.engine->renderState();
        const Mat4f& T = active.T_world_submap;
        world_render_.intrinsics = local.intrinsics;
        world_render_.T_world_camera = T * local.T_world_camera;
        copyTransformed(local.points_world, T, true, world_render_.points_world);
        copyTransformed(local.normals_world, T, false, world_render_.normals_world);
        world_render_version_ = frames_processed_;
        return world_render_;
    }
    // Renders show every submap at its pose now, as the map's surface: the last pose's from the depth camera.
    void renderLast(RenderMode mode, Image<Vec4u8>& image) override {
        renderFromPose(last_T_world_camera_, calib_.depth, mode, image);
    }
    void renderFromPose(const Mat4f& T_world_camera, const Intrinsics& intrinsics, RenderMode mode,
                        Image<Vec4u8>& image) override {
        renderFromPose(T_world_camera, intrinsics, mode, image, render_depth_);
    }
    // Each pixel from the submap whose surface is nearest the camera there, among the surfaces no other
    // submap that saw along the same ray observed better (bestObserved's rule): a submap keeps surface
    // that later views, fused into another submap, carved away (it saw the place from the edge of its
    // views only), and that surface must not hide the one behind it. The submaps not tracked against
    // release the raycast buffers their renders took.
    void renderFromPose(const Mat4f& T_world_camera, const Intrinsics& intrinsics, RenderMode mode,
                        Image<Vec4u8>& image, Image<float>& depth_m) override {
        const std::size_t n = submaps_.size();
        part_images_.resize(n);
        part_depths_.resize(n);
        for (std::size_t j = 0; j < n; ++j) {
            MainEngine& engine = *submaps_[j].engine;
            const Mat4f T_submap_camera = rigidInverse(submaps_[j].T_world_submap) * T_world_camera;
            engine.renderFromPose(T_submap_camera, intrinsics, mode, part_images_[j], part_depths_[j]);
            if (int(j) != active_ && int(j) != building_) engine.releaseFrameMemory();
        }
        const std::size_t pixels = std::size_t(intrinsics.width) * std::size_t(intrinsics.height);
        // hidden[j][i]: submap j's surface at pixel i is one another submap observed better. Asked only
        // where another submap's ray met a surface too: elsewhere there is nothing to choose.
        std::vector<std::vector<char>> hidden(n, std::vector<char>(pixels, 0));
        if (n > 1) {
            std::vector<Mat4f> T_world_submaps;
            for (const Submap& m : submaps_) T_world_submaps.push_back(m.T_world_submap);
            std::vector<Vec3f> points;  // submap j's surface points, its frame
            std::vector<std::size_t> at;
            for (std::size_t j = 0; j < n; ++j) {
                points.clear();
                at.clear();
                const Mat4f T_submap_camera = rigidInverse(T_world_submaps[j]) * T_world_camera;
                for (std::size_t i = 0; i < pixels; ++i) {
                    const float d = part_depths_[j].host()[i];
                    if (!(d > 0.f)) continue;
                    bool shared = false;
                    for (std::size_t k = 0; k < n && !shared; ++k) shared = k != j && part_depths_[k].host()[i] > 0.f;
                    if (!shared) continue;
                    const float u = float(i % std::size_t(intrinsics.width)),
                                v = float(i / std::size_t(intrinsics.width));
                    points.push_back(transformPoint(T_submap_camera, intrinsics.unproject(u, v, d)));
                    at.push_back(i);
                }
                if (points.empty()) continue;
                const std::vector<char> keep = bestObserved(int(j), points, T_world_submaps);
                for (std::size_t q = 0; q < points.size(); ++q) hidden[j][at[q]] = !keep[q];
            }
        }
        image.resize(intrinsics.size());
        depth_m.resize(intrinsics.size());
        for (std::size_t i = 0; i < pixels; ++i) {
            int best = -1;
            bool best_hidden = true;
            for (std::size_t j = 0; j < n; ++j) {
                const float d = part_depths_[j].host()[i];
                if (!(d > 0.f)) continue;
                const bool h = hidden[j][i] != 0;
                // A surface seen best wins over a hidden one; between alike, the nearer.
                if (best < 0 || (best_hidden && !h) ||
                    (best_hidden == h && d < part_depths_[std::size_t(best)].host()[i])) {
                    best = int(j);
                    best_hidden = h;
                }
            }
            const std::size_t from = best < 0 ? 0 : std::size_t(best);
            image.host()[i] = part_images_[from].host()[i];
            depth_m.host()[i] = best < 0 ? 0.f : part_depths_[from].host()[i];
        }
    }

    void reset() override {
        submaps_.clear();
        frame_poses_.clear();
        frames_processed_ = 0;
        loops_.clear();
        loop_joined_.clear();
        loop_edges_.clear();
        // Solutions of the old map's graph are not the new one's.
        optimiser_.waitIdle();
        PoseGraphResult old;
        solutions_adopted_ = solutions_before_map_ = optimiser_.latest(old);
        has_source_origin_ = false;
        T_source_world_ = Mat4f::identity();
        placing_ = false;
        startMap();
    }

    std::size_t sceneBytes() const override {
        std::size_t bytes = 0;
        for (const Submap& s : submaps_) bytes += s.engine->sceneBytes();
        return bytes;
    }
    AllocationStats allocationStats() const override { return submaps_[active_].engine->allocationStats(); }
    const TrackerStats& trackerStats() const override { return submaps_[active_].engine->trackerStats(); }

    // Every submap's surface at its optimised pose, each part of it from the submap that observed it
    // most (bestObserved): where submaps overlap, the union holds one surface, not each one's.
    void extractMesh(Mesh& mesh) override {
        mesh.clear();
        const std::vector<Mat4f> T_world_submaps = optimisedSubmapPoses();
        for (std::size_t i = 0; i < submaps_.size(); ++i) {
            Mesh part;
            submaps_[i].engine->extractMesh(part);
            std::vector<Vec3f> centres;
            centres.reserve(part.triangles.size());
            for (const Vec3i& t : part.triangles)
                centres.push_back((part.vertices[t.x] + part.vertices[t.y] + part.vertices[t.z]) * (1.f / 3.f));
            const std::vector<char> keep = bestObserved(int(i), centres, T_world_submaps);
            // The kept triangles' vertices, in the order the triangles first use them.
            std::vector<int> index_in_union(part.vertices.size(), -1);
            const Mat4f& T = T_world_submaps[i];
            for (std::size_t k = 0; k < part.triangles.size(); ++k) {
                if (!keep[k]) continue;
                Vec3i t = part.triangles[k];
                for (int* corner : {&t.x, &t.y, &t.z}) {
                    int& u = index_in_union[std::size_t(*corner)];
                    if (u < 0) {
                        u = int(mesh.vertices.size());
                        const std::size_t v = std::size_t(*corner);
                        mesh.vertices.push_back(transformPoint(T, part.vertices[v]));
                        if (part.hasNormals()) mesh.normals.push_back(transformDirection(T, part.normals[v]));
                        if (part.hasColors()) mesh.colors.push_back(part.colors[v]);
                        if (part.hasLabels()) mesh.labels.push_back(part.labels[v]);
                    }
                    *corner = u;
                }
                mesh.triangles.push_back(t);
            }
        }
    }
    void extractPointCloud(PointCloud& cloud) override {
        cloud.clear();
        const std::vector<Mat4f> T_world_submaps = optimisedSubmapPoses();
        for (std::size_t i = 0; i < submaps_.size(); ++i) {
            PointCloud part;
            submaps_[i].engine->extractPointCloud(part);
            const std::vector<char> keep = bestObserved(int(i), part.points, T_world_submaps);
            const Mat4f& T = T_world_submaps[i];
            for (std::size_t k = 0; k < part.points.size(); ++k) {
                if (!keep[k]) continue;
                cloud.points.push_back(transformPoint(T, part.points[k]));
                if (part.hasNormals()) cloud.normals.push_back(transformDirection(T, part.normals[k]));
                if (part.hasColors()) cloud.colors.push_back(part.colors[k]);
                if (part.hasLabels()) cloud.labels.push_back(part.labels[k]);
            }
        }
    }
    // The highest depth weight any submap has at each point (the world frame).
    void depthWeightsAt(const std::vector<Vec3f>& points_world, std::vector<float>& weights) override {
        const std::vector<Mat4f> T_world_submaps = optimisedSubmapPoses();
        weights.assign(points_world.size(), 0.f);
        std::vector<Vec3f> local(points_world.size());
        std::vector<float> w;
        for (std::size_t j = 0; j < submaps_.size(); ++j) {
            const Mat4f T_submap_world = rigidInverse(T_world_submaps[j]);
            for (std::size_t k = 0; k < points_world.size(); ++k)
                local[k] = transformPoint(T_submap_world, points_world[k]);
            submaps_[j].engine->depthWeightsAt(local, w);
            for (std::size_t k = 0; k < w.size(); ++k) weights[k] = std::max(weights[k], w[k]);
        }
    }

    // The submaps at their poses as the pose graph last solved them (a solve in progress is waited
    // for), the graph's edges, and each submap's map with its keyframes.
    void saveMap(const std::string& path) override {
        optimiser_.waitIdle();
        adoptSolution();
        SubmapMapInfo info;
        info.map.voxel_type = toString(settings_.voxel_type);
        info.map.hash = true;
        info.map.hash_settings = settings_.hash;
        info.map.scene = settings_.scene;
        info.map.T_world_camera = last_T_world_camera_;
        info.map.has_origin = has_source_origin_;
        info.map.T_source_world = T_source_world_;
        info.map.camera = calib_.depth;
        info.active = active_;
        for (const Submap& m : submaps_) {
            info.T_world_submap.push_back(m.T_world_submap);
            info.parent.push_back(m.parent);
        }
        info.edges = graph_.edges();
        MapFileWriter file(path);
        writeSubmapMapHeader(file, info);
        for (Submap& m : submaps_) m.engine->saveMapInto(file);
        writeSubmapMapEnd(file);
        file.commit();
    }

    // A map of submaps, or a single map as the first submap. Read into new submaps first: a file that
    // fails leaves the map as it was. The run goes on in the active submap; its first frame is looked
    // up there and then in every submap in turn (relocaliseInOtherSubmaps) before anything is fused.
    MapFileInfo loadMap(const std::string& path) override {
        MapFileReader file(path);
        SubmapMapInfo info;
        if (file.holdsSubmaps()) {
            info = readSubmapMapHeader(file);
        } else {
            info.map = file.nextMapInfo();
            info.T_world_submap = {Mat4f::identity()};
            info.parent = {-1};
        }
        std::vector<Submap> loaded;
        for (std::size_t i = 0; i < info.T_world_submap.size(); ++i) {
            const MapFileInfo& part = file.nextMapInfo();
            if (part.voxel_type != toString(settings_.voxel_type) || !part.hash ||
                part.scene.voxel_size_m != settings_.scene.voxel_size_m || part.scene.mu_m != settings_.scene.mu_m)
                throw IoError(path, "submap " + std::to_string(i) + " holds '" + part.voxel_type + "' voxels of " +
                                        std::to_string(part.scene.voxel_size_m) +
                                        " m, not the map's (settingsForMap makes settings that fit)");
            Submap m;
            // Its table as saved (it may have grown), its block ceiling the submaps'.
            MainEngineSettings part_settings = settingsForMap(part, local_settings_);
            part_settings.hash.max_block_count = local_settings_.hash.max_block_count;
            m.engine = MainEngine::create(part_settings, calib_);
            m.engine->loadMapFrom(file);
            m.T_world_submap = info.T_world_submap[i];
            m.parent = info.parent[i];
            m.keyframes = -1;  // unknown until it tracks a frame
            loaded.push_back(std::move(m));
        }
        if (info.map.submap_count > 0)
            readSubmapMapEnd(file);
        else
            file.requireEnd();

        reset();
        submaps_ = std::move(loaded);
        graph_ = PoseGraph();
        for (const Submap& m : submaps_) graph_.addNode(m.T_world_submap);
        for (const PoseGraphEdge& e : info.edges) {
            graph_.addEdge(e);
            if (e.loop) loop_joined_.insert({std::min(e.from, e.to), std::max(e.from, e.to)});
        }
        active_ = info.active;
        last_T_world_camera_ = info.map.T_world_camera;
        has_source_origin_ = info.map.has_origin;
        T_source_world_ = info.map.T_source_world;
        for (std::size_t i = 0; i < submaps_.size(); ++i)
            if (int(i) != active_) submaps_[i].engine->releaseFrameMemory();
        placing_ = true;
        place_cursor_ = 0;
        MapFileInfo whole = info.map;
        whole.submap_count = int(submaps_.size());
        return whole;
    }
    void saveMapInto(MapFileWriter&) override {
        throw ConfigError("a map of submaps is a file of its own: it cannot be saved as one map among others");
    }
    MapFileInfo loadMapFrom(MapFileReader& file) override {
        throw ConfigError(file.path() + ": a map of submaps loads from a file of its own (loadMap)");
    }
    std::vector<Mat4f> keyframePoses() const override {
        std::vector<Mat4f> poses;
        for (const Submap& m : submaps_)
            for (const Mat4f& T : m.engine->keyframePoses()) poses.push_back(m.T_world_submap * T);
        return poses;
    }

    // The other map is loaded as a map of its own first; its submaps are moved here only once one of
    // them is found, so a failure leaves this map as it was. Places are recognised between renders of
    // both maps (fern codes, engines/FernEncoder.h): a render holds the map's surface only, without
    // what its frames saw beyond the fused range, so renders compare with renders, not with frames.
    // Each of the other map's views is then aligned to the submaps here from the poses of the views
    // most like it (locateNear) and accepted by relocalisation's check.
    std::vector<LoopClosure> mergeMap(const std::string& path) override {
        SubmapEngine other(settings_, calib_);
        other.loadMap(path);
        optimiser_.waitIdle();
        adoptSolution();
        // Rendered views become frames of a camera with the map's depth intrinsics and colour in the
        // depth camera's place; an engine of the same settings converts them into views.
        RGBDCalib view_calib;
        view_calib.depth = view_calib.rgb = calib_.depth;
        view_calib.disparity = DisparityCalib::affine(kRenderedDepthStepM);
        const bool color = voxelTypeHasColor(settings_.voxel_type);
        FernEncoder encoder(settings_.relocalisation.ferns, calib_.depth.size(), color);
        const std::vector<PlaceView> here = placeViews(*this, view_calib, color, encoder, kMergeViewsHere);
        const std::vector<PlaceView> there = placeViews(other, view_calib, color, encoder, kMergeViewsThere);
        auto converter = MainEngine::create(local_settings_, view_calib);
        const int offset = static_cast<int>(submaps_.size());
        std::vector<PoseGraphEdge> joins;
        std::vector<LoopClosure> reports;
        std::vector<char> joined(other.submaps_.size(), 0);
        for (const PlaceView& view : there) {
            if (joined[std::size_t(view.submap)]) continue;
            // The views here most like it.
            std::vector<std::pair<float, std::size_t>> alike;
            for (std::size_t h = 0; h < here.size(); ++h)
                alike.push_back({fernDissimilarity(view.code, here[h].code), h});
            const std::size_t candidates = std::min(alike.size(), std::size_t(settings_.relocalisation.candidates));
            std::partial_sort(alike.begin(), alike.begin() + std::ptrdiff_t(candidates), alike.end());
            MainEngine& part = *other.submaps_[std::size_t(view.submap)].engine;
            const Mat4f identity = Mat4f::identity();
            converter->reset();
            converter->processFrame(renderedFrame(part, view.T_submap_camera, view_calib, color), &identity);
            for (std::size_t c = 0; c < candidates; ++c) {
                const PlaceView& like = here[alike[c].second];
                MainEngine& engine = *submaps_[std::size_t(like.submap)].engine;
                TrackingState found;
                const bool located = engine.locateNear(converter->view(), like.T_submap_camera, found);
                if (like.submap != active_) engine.releaseFrameMemory();
                if (!located) continue;
                joins.push_back(
                    submap_edges::loop(like.submap, offset + view.submap, found.T_world_camera, view.T_submap_camera));
                reports.push_back(loopReport(-1, like.submap, offset + view.submap, found));
                joined[std::size_t(view.submap)] = 1;
                break;
            }
        }
        for (Submap& m : other.submaps_) m.engine->releaseFrameMemory();
        if (joins.empty())
            throw Error(path + ": no view of the map was found in this one (" + std::to_string(other.submaps_.size()) +
                        " submaps tried): they do not overlap, or not where either has keyframes");

        // The other map's world placed by its first join; the pose graph weighs the others.
        const PoseGraphEdge& first = joins.front();
        const Mat4f T_world_other = submaps_[std::size_t(first.from)].T_world_submap * first.T_from_to *
                                    rigidInverse(other.submaps_[std::size_t(first.to - offset)].T_world_submap);
        for (Submap& m : other.submaps_) {
            m.T_world_submap = T_world_other * m.T_world_submap;
            // Its first submap hangs from the submap it was first found in.
            m.parent = m.parent >= 0 ? m.parent + offset : first.from;
            m.keyframes = -1;
            graph_.addNode(m.T_world_submap);
            submaps_.push_back(std::move(m));
        }
        for (PoseGraphEdge e : other.graph_.edges()) {
            e.from += offset;
            e.to += offset;
            graph_.addEdge(e);
        }
        for (std::size_t q = 0; q < joins.size(); ++q) addLoop(joins[q], reports[q]);
        for (const auto& [a, b] : other.loop_joined_) loop_joined_.insert({a + offset, b + offset});
        optimiser_.submit(graph_);
        world_render_version_ = -1;
        return reports;
    }

    void setSourceOrigin(const Mat4f& T_source_world) override {
        T_source_world_ = T_source_world;
        has_source_origin_ = true;
    }
    bool sourceOrigin(Mat4f& T_source_world) const override {
        if (has_source_origin_) T_source_world = T_source_world_;
        return has_source_origin_;
    }

    bool optimisedPoses(std::vector<Mat4f>& T_world_camera) override {
        const std::vector<Mat4f> T_world_submaps = optimisedSubmapPoses();
        T_world_camera.clear();
        T_world_camera.reserve(frame_poses_.size());
        for (const FramePose& f : frame_poses_) T_world_camera.push_back(T_world_submaps[f.submap] * f.T_submap_camera);
        return true;
    }
    int submapCount() const override { return static_cast<int>(submaps_.size()); }
    std::vector<SubmapPose> submapPoses() const override {
        std::vector<SubmapPose> poses;
        for (const Submap& m : submaps_) poses.push_back({m.T_world_submap, m.parent});
        return poses;
    }
    float modelCoverage(const View& view) override { return submaps_[active_].engine->modelCoverage(view); }

    void releaseFrameMemory() override {
        for (Submap& m : submaps_) m.engine->releaseFrameMemory();
        world_render_version_ = -1;
    }

    PoseGraphSolveStats poseGraphSolves() override {
        optimiser_.waitIdle();
        return optimiser_.solveStats();
    }

    std::vector<LoopClosure> loopClosures() override {
        std::vector<LoopClosure> loops = loops_;
        if (loops.empty()) return loops;
        optimiser_.waitIdle();
        PoseGraphResult solved;
        if (optimiser_.latest(solved) > solutions_before_map_)
            for (std::size_t k = 0; k < loops.size(); ++k) {
                const std::size_t e = static_cast<std::size_t>(loop_edges_[k]);
                if (e < solved.edge_chi2.size()) {
                    loops[k].chi2 = solved.edge_chi2[e];
                    loops[k].rejected = solved.edge_rejected[e];
                }
            }
        return loops;
    }

private:
    struct Submap {
        std::unique_ptr<MainEngine> engine;
        // As tracked, then as the pose graph last optimised it (the initial value of its next solve).
        Mat4f T_world_submap = Mat4f::identity();
        int parent = -1;    // the submap it started from (joined by odometry)
        int keyframes = 0;  // its engine's, after the last frame it tracked
    };
    struct FramePose {
        int submap;
        Mat4f T_submap_camera;
    };

    // Which of submap i's surface points (its frame) it observed best: no other submap has a higher
    // depth weight there, nor an older one as high (one owner where weights saturate alike). A point
    // no other submap observed stays, whatever its own weight.
    std::vector<char> bestObserved(int i, const std::vector<Vec3f>& points, const std::vector<Mat4f>& T_world_submaps) {
        std::vector<float> own, other;
        submaps_[std::size_t(i)].engine->depthWeightsAt(points, own);
        std::vector<char> keep(points.size(), 1);
        std::vector<Vec3f> there(points.size());
        for (int j = 0; j < int(submaps_.size()); ++j) {
            if (j == i) continue;
            const Mat4f T_j_i = rigidInverse(T_world_submaps[std::size_t(j)]) * T_world_submaps[std::size_t(i)];
            for (std::size_t k = 0; k < points.size(); ++k) there[k] = transformPoint(T_j_i, points[k]);
            submaps_[std::size_t(j)].engine->depthWeightsAt(there, other);
            for (std::size_t k = 0; k < points.size(); ++k)
                if (other[k] > own[k] || (other[k] > 0.f && other[k] == own[k] && j < i)) keep[k] = 0;
        }
        return keep;
    }

    // A submap's view for recognising places between maps: rendered from T_submap_camera, encoded.
    struct PlaceView {
        int submap;
        Mat4f T_submap_camera;
        FernCode code;
    };
    // Every submap of `map` seen from its first camera and from its keyframes' poses (at most `per_submap`
    // views, spread over them).
    static std::vector<PlaceView> placeViews(SubmapEngine& map, const RGBDCalib& view_calib, bool color,
                                             FernEncoder& encoder, int per_submap) {
        std::vector<PlaceView> views;
        for (int j = 0; j < static_cast<int>(map.submaps_.size()); ++j) {
            MainEngine& part = *map.submaps_[std::size_t(j)].engine;
            std::vector<Mat4f> poses = {Mat4f::identity()};
            for (const Mat4f& T : spread(part.keyframePoses(), per_submap - 1)) poses.push_back(T);
            for (const Mat4f& T : poses) {
                Image<Vec4u8> image;
                Image<float> depth_m;
                part.renderFromPose(T, view_calib.depth, RenderMode::Color, image, depth_m);
                if (!color) image = Image<Vec4u8>();
                views.push_back({j, T, encoder.encode(depth_m, image)});
            }
            if (j != map.active_) part.releaseFrameMemory();
        }
        return views;
    }

    // The first submap; its frame is the world.
    void startMap() {
        Submap first;
        first.engine = MainEngine::create(local_settings_, calib_);
        submaps_.push_back(std::move(first));
        graph_ = PoseGraph();
        graph_.addNode(Mat4f::identity());
        active_ = 0;
        building_ = -1;
        overlap_left_ = 0;
        last_T_world_camera_ = Mat4f::identity();
        world_render_version_ = -1;
    }

    // A new submap whose frame is the camera's now; `frame` is its first.
    void startSubmap(const RGBDFrame& frame, const Mat4f& T_world_camera, const Mat4f& T_active_camera) {
        Submap next;
        next.engine = MainEngine::create(local_settings_, calib_);
        next.T_world_submap = T_world_camera;
        next.parent = active_;
        const Mat4f identity = Mat4f::identity();
        next.engine->processFrame(frame, &identity);
        submaps_.push_back(std::move(next));
        const int index = graph_.addNode(T_world_camera);

        graph_.addEdge(submap_edges::odometry(active_, index, T_active_camera));
        optimiser_.submit(graph_);

        building_ = index;
        overlap_left_ = submap_settings_.overlap_frames;
        if (overlap_left_ <= 0) switchTo(index);
    }

    // Looks the frame up in the older submaps nearest to the camera (by their poses now); on success
    // joins the two submaps by a loop edge and makes the older one active again: the camera is tracked
    // against the map it made there before, as it would be without submaps. Returns whether it did.
    bool searchLoop(const RGBDFrame& frame, const Mat4f& T_active_camera) {
        const Mat4f T_world_camera = submaps_[active_].T_world_submap * T_active_camera;
        std::vector<std::pair<float, int>> nearest;
        for (int j = 0; j < static_cast<int>(submaps_.size()); ++j) {
            // Not a submap a loop joins to the active one already: their relative pose is measured, and
            // the camera, just handed over between them, would be handed back and forth. (The submap
            // one started from is a revisit's: the camera comes back to where it started it.)
            if (j == active_ || j == building_ || loopJoined(j, active_)) continue;
            // Only where the camera is back well inside the submap's neighbourhood by the poses now: a
            // camera at its edge would start a new submap at once, and one hovering there would switch
            // back and forth.
            const Mat4f T_j_camera = rigidInverse(submaps_[j].T_world_submap) * T_world_camera;
            if (!withinNeighbourhood(T_j_camera, kLoopSearchShare)) continue;
            nearest.push_back({distanceM(T_j_camera), j});
        }
        std::sort(nearest.begin(), nearest.end());
        const View& view = submaps_[active_].engine->view();
        for (std::size_t k = 0; k < nearest.size() && k < std::size_t(kLoopSubmapsPerFrame); ++k) {
            const int j = nearest[k].second;
            TrackingState found;
            if (!locateIn(j, view, T_world_camera, found)) continue;

            addLoop(submap_edges::loop(j, active_, found.T_world_camera, T_active_camera),
                    loopReport(static_cast<int>(frames_processed_) - 1, j, active_, found));
            optimiser_.submit(graph_);

            // The frame is fused into the older submap at the pose found there, which is tracked from here.
            if (!withinNeighbourhood(found.T_world_camera, 1.f)) {
                submaps_[std::size_t(j)].engine->releaseFrameMemory();
                return false;
            }
            submaps_[j].engine->processFrame(frame, &found.T_world_camera);
            switchTo(j);
            return true;
        }
        return false;
    }

    // Lost in the active submap: the frame is looked up in the other submaps near the last good pose,
    // as a loop is (their keyframes may hold the view); found, it is fused there and that submap is
    // tracked against from here. `result` becomes the frame's, relocalised.
    // After a map was loaded, until a frame is placed, every submap is a candidate, whatever its
    // distance (the new recording may start anywhere in the map): kLoopSubmapsPerFrame of them per
    // frame, in turn, nearest to the saved pose first.
    void relocaliseInOtherSubmaps(const RGBDFrame& frame, FrameResult& result) {
        std::vector<std::pair<float, int>> nearest;
        for (int j = 0; j < static_cast<int>(submaps_.size()); ++j) {
            if (j == active_) continue;
            const Mat4f T_j_camera = rigidInverse(submaps_[j].T_world_submap) * result.T_world_camera;
            if (placing_ || withinNeighbourhood(T_j_camera, 1.f)) nearest.push_back({distanceM(T_j_camera), j});
        }
        std::sort(nearest.begin(), nearest.end());
        if (placing_ && !nearest.empty()) {
            std::rotate(nearest.begin(), nearest.begin() + std::ptrdiff_t(place_cursor_ % nearest.size()),
                        nearest.end());
            place_cursor_ += kLoopSubmapsPerFrame;
        }
        const View& view = submaps_[active_].engine->view();
        for (std::size_t k = 0; k < nearest.size() && k < std::size_t(kLoopSubmapsPerFrame); ++k) {
            const int j = nearest[k].second;
            TrackingState found;
            if (!locateIn(j, view, result.T_world_camera, found)) continue;
            submaps_[j].engine->processFrame(frame, &found.T_world_camera);
            switchTo(j);
            result.fused = true;
            result.status = TrackingStatus::Relocalised;
            result.quality = found.quality;
            result.tracking = found;
            toWorld(submaps_[j].T_world_submap, result.tracking);
            result.T_world_camera = result.tracking.T_world_camera;
            frame_poses_.push_back({j, found.T_world_camera});
            last_T_world_camera_ = result.T_world_camera;
            placing_ = false;
            return;
        }
    }

    // The frame in `view` looked up in submap j: by its keyframes first (MainEngine::locate); then, as a
    // revisit seen from another angle (a keyframe is recognised within a few degrees of its view),
    // aligned to the submap's model from where the poses put the camera, `T_world_camera` in the
    // submap's frame (locateNear). The search fills j's tracker and raycast buffers: they are released
    // again unless j is to be tracked against.
    bool locateIn(int j, const View& view, const Mat4f& T_world_camera, TrackingState& found) {
        MainEngine& engine = *submaps_[std::size_t(j)].engine;
        const Mat4f T_j_camera = rigidInverse(submaps_[std::size_t(j)].T_world_submap) * T_world_camera;
        const bool located = engine.locate(view, found) || engine.locateNear(view, T_j_camera, found);
        if (!located) engine.releaseFrameMemory();
        return located;
    }

    static LoopClosure loopReport(int frame, int from, int to, const TrackingState& found) {
        LoopClosure report;
        report.frame = frame;
        report.from_submap = from;
        report.to_submap = to;
        report.residual_m = found.residual_m;
        report.inlier_ratio = found.inlier_ratio;
        return report;
    }
    // Into the graph (solved when next submitted), reported, and its submaps marked as joined.
    void addLoop(const PoseGraphEdge& edge, const LoopClosure& report) {
        loop_edges_.push_back(graph_.edgeCount());
        graph_.addEdge(edge);
        loop_joined_.insert({std::min(edge.from, edge.to), std::max(edge.from, edge.to)});
        loops_.push_back(report);
    }

    bool loopJoined(int a, int b) const { return loop_joined_.count({std::min(a, b), std::max(a, b)}) > 0; }

    // Whether a camera at T_submap_camera is within `share` of the distance that starts a new submap.
    bool withinNeighbourhood(const Mat4f& T_submap_camera, float share) const {
        return distanceM(T_submap_camera) <= share * submap_settings_.max_distance_m;
    }

    // The pose graph's newest solution becomes the submaps' poses (the camera's pose in the world moves
    // with its submap's; within the submap tracking is undisturbed).
    void adoptSolution() {
        if (optimiser_.solvedCount() == solutions_adopted_) return;  // every frame: no copy unless new
        PoseGraphResult solved;
        const int count = optimiser_.latest(solved);
        solutions_adopted_ = count;
        // Submaps started after that graph was handed over move as the submap they started from did.
        std::vector<Mat4f> before;
        for (const Submap& m : submaps_) before.push_back(m.T_world_submap);
        for (std::size_t i = 0; i < submaps_.size(); ++i) {
            Submap& m = submaps_[i];
            if (i < solved.T_world_node.size())
                m.T_world_submap = solved.T_world_node[i];
            else if (m.parent >= 0)
                m.T_world_submap = submaps_[m.parent].T_world_submap * rigidInverse(before[m.parent]) * before[i];
            graph_.setNode(static_cast<int>(i), m.T_world_submap);
        }
    }

    // The submaps not tracked against from here keep their maps and keyframes, not their frame buffers.
    void switchTo(int submap) {
        for (const int left : {active_, building_})
            if (left >= 0 && left != submap) submaps_[std::size_t(left)].engine->releaseFrameMemory();
        active_ = submap;
        building_ = -1;
        world_render_version_ = -1;
    }

    // The submaps' poses as the pose graph last optimised them; as tracked before any solve.
    std::vector<Mat4f> optimisedSubmapPoses() {
        std::vector<Mat4f> poses;
        for (const Submap& s : submaps_) poses.push_back(s.T_world_submap);
        if (submaps_.size() < 2) return poses;
        optimiser_.waitIdle();
        PoseGraphResult solved;
        if (optimiser_.latest(solved) > solutions_before_map_)
            for (std::size_t i = 0; i < solved.T_world_node.size() && i < poses.size(); ++i)
                poses[i] = solved.T_world_node[i];
        return poses;
    }

    static void copyTransformed(const Image<Vec4f>& from, const Mat4f& T, bool points, Image<Vec4f>& to) {
        if (to.size().x != from.size().x || to.size().y != from.size().y) to.resize(from.size());
        const Vec4f* src = from.host();
        Vec4f* dst = to.host();
        for (std::size_t i = 0; i < from.pixelCount(); ++i) {
            const Vec3f p{src[i].x, src[i].y, src[i].z};
            const Vec3f q = points ? transformPoint(T, p) : transformDirection(T, p);
            dst[i] = {q.x, q.y, q.z, src[i].w};
        }
    }

    RGBDCalib calib_;
    SubmapSettings submap_settings_;
    MainEngineSettings local_settings_;  // each submap's engine's: submaps off
    MainEngineSettings settings_;        // as reported: submaps on, the map's tables, a submap's block ceiling
    std::vector<Submap> submaps_;
    int active_ = 0;                      // tracked against and fused into
    int building_ = -1;                   // during an overlap: the new submap, fused into too
    int overlap_left_ = 0;                // frames until it becomes the active one
    std::vector<FramePose> frame_poses_;  // of the frames with a pose (not the lost ones)
    long long frames_processed_ = 0;      // since the map began
    std::vector<LoopClosure> loops_;
    std::vector<int> loop_edges_;                // each loop's edge in graph_
    std::set<std::pair<int, int>> loop_joined_;  // submap pairs a loop edge joins, (lower, higher)
    int solutions_adopted_ = 0;
    int solutions_before_map_ = 0;  // solved before the last reset()
    Mat4f last_T_world_camera_ = Mat4f::identity();
    mutable TrackingState tracking_;
    mutable RenderState world_render_;
    std::vector<Image<Vec4u8>> part_images_;  // renderFromPose: each submap's render and depth
    std::vector<Image<float>> part_depths_;
    Image<float> render_depth_;
    mutable long long world_render_version_ = -1;
    bool has_source_origin_ = false;
    Mat4f T_source_world_ = Mat4f::identity();
    bool placing_ = false;          // a map was loaded and no frame is placed in it yet
    std::size_t place_cursor_ = 0;  // the submaps searched so far while placing
    PoseGraph graph_;
    PoseGraphOptimiser optimiser_;
};

}  // namespace

std::unique_ptr<MainEngine> makeSubmapEngine(const MainEngineSettings& checked_settings, const RGBDCalib& calib) {
    return std::make_unique<SubmapEngine>(checked_settings, calib);
}

}  // namespace voxfuse
