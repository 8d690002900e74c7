// TUM trajectories ("timestamp tx ty tz qx qy qz qw", camera-to-world) and pose interpolation.

#include "voxfuse/io/TrajectoryIO.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <locale>

#include <Eigen/Geometry>

#include "TextParsing.h"
#include "voxfuse/io/AtomicFile.h"
#include "voxfuse/core/EigenInterop.h"
#include "voxfuse/core/Error.h"

namespace voxfuse {

namespace {

Mat4f poseFrom(const Eigen::Vector3d& t, const Eigen::Quaterniond& q) {
    Eigen::Matrix4f T = Eigen::Matrix4f::Identity();
    T.topLeftCorner<3, 3>() = q.toRotationMatrix().cast<float>();
    T.topRightCorner<3, 1>() = t.cast<float>();
    return toMat4f(T);
}

Eigen::Quaterniond rotationOf(const Mat4f& T) {
    const Eigen::Matrix3d R = toEigen(T).topLeftCorner<3, 3>().cast<double>();
    Eigen::Quaterniond q(R);
    q.normalize();  // float round-off leaves R slightly off a rotation
    // q and -q are the same rotation; a fixed sign keeps written files stable and diffable.
    if (q.w() < 0.0) q.coeffs() = -q.coeffs();
    return q;
}

Eigen::Vector3d translationOf(const Mat4f& T) { return {T(0, 3), T(1, 3), T(2, 3)}; }

}  // namespace

std::vector<TimedPose> readTumTrajectory(const std::string& path) {
    text::LineReader in(path, "trajectory file");
    std::vector<TimedPose> poses;
    std::string line;
    int previous_line = 0;
    while (in.next(line)) {
        const int line_number = in.lineNumber();
        if (text::isBlankOrComment(line)) continue;
        const auto tokens = text::splitWhitespace(line);
        if (tokens.size() != 8)
            throw ParseError(
                path, line_number,
                "expected 8 numbers (timestamp tx ty tz qx qy qz qw), got " + std::to_string(tokens.size()));
        std::vector<double> v;
        std::string bad;
        if (!text::parseDoubles(tokens, v, bad))
            throw ParseError(path, line_number, "not a number: " + text::excerpt(bad));
        if (!std::isfinite(v[0]))
            throw ParseError(path, line_number, "non-finite timestamp " + text::excerpt(tokens[0]));
        for (int i = 1; i < 4; ++i)
            if (!text::finiteAsFloat(v[std::size_t(i)]))
                throw ParseError(
                    path, line_number,
                    "non-finite position " + text::excerpt(tokens[std::size_t(i)]) + " (stored as a float)");
        std::string problem = text::positionProblem(v[1], v[2], v[3]);
        if (problem.empty()) problem = text::quaternionProblem(v[4], v[5], v[6], v[7]);
        if (!problem.empty()) throw ParseError(path, line_number, problem);
        Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);  // Eigen takes (w, x, y, z)
        q.normalize();
        const TimedPose pose{v[0], poseFrom({v[1], v[2], v[3]}, q)};
        if (!poses.empty() && v[0] < poses.back().timestamp_s)
            throw ParseError(path, line_number,
                             "timestamps must not decrease (" + std::string(tokens[0]) + " comes after a later one)");
        if (!poses.empty() && v[0] == poses.back().timestamp_s) {
            // The same sample written twice is harmless; two poses for one time are a broken file.
            const Mat4f& earlier = poses.back().T_world_camera;
            if (!std::equal(std::begin(earlier.m), std::end(earlier.m), std::begin(pose.T_world_camera.m)))
                throw ParseError(path, line_number,
                                 "timestamp " + std::string(tokens[0]) + " is given twice (line " +
                                     std::to_string(previous_line) + ") with different poses");
            continue;
        }
        poses.push_back(pose);
        previous_line = line_number;
    }
    return poses;
}

void writeTumTrajectory(const std::string& path, const std::vector<TimedPose>& poses) {
    AtomicFile file(path);
    std::ostream& out = file.stream();
    out.imbue(std::locale::classic());
    out << "# timestamp tx ty tz qx qy qz qw\n";
    for (const TimedPose& p : poses) {
        const Eigen::Vector3d t = translationOf(p.T_world_camera);
        const Eigen::Quaterniond q = rotationOf(p.T_world_camera);
        // Microsecond timestamps as TUM writes them; 9 significant digits reproduce a float exactly.
        out << std::fixed << std::setprecision(6) << p.timestamp_s << std::defaultfloat << std::setprecision(9);
        out << ' ' << t.x() << ' ' << t.y() << ' ' << t.z() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' '
            << q.w() << '\n';
    }
    file.commit();
}

bool interpolatePose(const std::vector<TimedPose>& poses, double t, double max_gap_s, Mat4f& T_world_camera) {
    if (poses.empty()) return false;
    const auto after = std::lower_bound(poses.begin(), poses.end(), t,
                                        [](const TimedPose& p, double time) { return p.timestamp_s < time; });
    const TimedPose* next = after != poses.end() ? &*after : nullptr;
    const TimedPose* prev = after != poses.begin() ? &*(after - 1) : nullptr;
    if (next && next->timestamp_s == t) {  // exact sample: no round trip through quaternions
        T_world_camera = next->T_world_camera;
        return true;
    }
    const bool next_ok = next && next->timestamp_s - t <= max_gap_s;
    const bool prev_ok = prev && t - prev->timestamp_s <= max_gap_s;

    if (next_ok && prev_ok && next->timestamp_s > prev->timestamp_s) {
        const double alpha = (t - prev->timestamp_s) / (next->timestamp_s - prev->timestamp_s);
        const Eigen::Vector3d trans =
            (1.0 - alpha) * translationOf(prev->T_world_camera) + alpha * translationOf(next->T_world_camera);
        const Eigen::Quaterniond rot = rotationOf(prev->T_world_camera).slerp(alpha, rotationOf(next->T_world_camera));
        T_world_camera = poseFrom(trans, rot);
        return true;
    }
    if (next_ok && (!prev_ok || next->timestamp_s - t <= t - prev->timestamp_s)) {
        T_world_camera = next->T_world_camera;
        return true;
    }
    if (prev_ok) {
        T_world_camera = prev->T_world_camera;
        return true;
    }
    return false;
}

std::vector<TimedPose> withPoses(const std::vector<TimedPose>& poses, const std::vector<Mat4f>& T_world_camera) {
    if (T_world_camera.size() != poses.size()) return poses;
    std::vector<TimedPose> replaced = poses;
    for (std::size_t i = 0; i < replaced.size(); ++i) replaced[i].T_world_camera = T_world_camera[i];
    return replaced;
}

}  // namespace voxfuse
