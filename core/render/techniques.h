// The sampling techniques of SPEC §3 by name: `bsdf` and `<selection>/<sampler>`.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "lights/light.h"

namespace omis {

enum class LightSelection { Uniform, Power, Unoccluded };

struct Technique {
    bool bsdf = false;  // cosine-weighted hemisphere
    LightSelection selection = LightSelection::Uniform;
    LightSampler sampler = LightSampler::SolidAngle;

    std::string name() const;
    bool operator==(const Technique& o) const {
        return bsdf == o.bsdf && (bsdf || (selection == o.selection && sampler == o.sampler));
    }
};

// "bsdf", "uniform/area", "power/solid-angle", "unoccluded/parallel",
// "uniform/projected-solid-angle", ...
std::optional<Technique> parse_technique(std::string_view name);

}  // namespace omis
