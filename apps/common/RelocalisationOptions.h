#pragma once
// The relocalisation options every front-end offers (voxfuse, voxfuse_viewer, voxfuse_bench).

#include <CLI/CLI.hpp>

#include "OptionChecks.h"
#include "voxfuse/engines/Relocaliser.h"

namespace voxfuse::app {

// --relocalise on|off, --relocalise-candidates N, --relocalise-max-speed M and
// --relocalise-min-color-correlation C (formerly -colour-), written into `settings`
// (kept alive by the caller).
inline void addRelocalisationOptions(CLI::App& cli, RelocalisationSettings& settings) {
    cli.add_option_function<std::string>(
           "--relocalise", [&settings](const std::string& mode) { settings.enabled = mode == "on"; },
           "once tracking is lost, find the camera again from keyframes (nothing is fused until then)")
        ->default_str(settings.enabled ? "on" : "off")
        ->check(CLI::IsMember({"on", "off"}));
    cli.add_option("--relocalise-candidates", settings.candidates,
                   "relocalisation: keyframes tried per lost frame, most alike first")
        ->capture_default_str()
        ->check(app::intIn(1, 1000));
    cli.add_option("--relocalise-max-speed", settings.max_speed_m_per_s,
                   "relocalisation: m/s the camera may have moved since the last good frame; poses farther away are "
                   "not taken (0: no limit)")
        ->capture_default_str()
        ->check(app::floatIn(0.0, 1e6));
    CLI::Option* correlation =
        cli.add_option("--relocalise-min-color-correlation", settings.min_color_correlation,
                       "relocalisation: how well a found pose's view must correlate with the map's colours (colour "
                       "voxels; -1: no colour test)")
            ->capture_default_str()
            ->check(app::floatIn(-1.0, 1.0));
    addFormerSpelling(cli, "--relocalise-min-colour-correlation", correlation, settings.min_color_correlation)
        ->check(app::floatIn(-1.0, 1.0));
}

}  // namespace voxfuse::app
