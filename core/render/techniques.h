// The sampling techniques of SPEC §3 by name: `bsdf` and `<selection>/<sampler>`.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "lights/light.h"

namespace omis {

// How a light technique selects its light (a technique's `<selection>`):
// the rule, where a LightSelector (render/light_selection.h) is the structure
// some rules draw from (uniform and power among many lights, tree).
// Tree: the light hierarchy's estimate of each light's contribution
// (render/light_selection.h) — cheap at any light count, unlike Unoccluded's
// exact per-light irradiance. Defensive: half Unoccluded's probabilities and
// half uniform over the lights that reach the point (a defensive mixture,
// Hesterberg 1995): one technique that keeps shadowed lights sampled, where
// an unoccluded + uniform pair would split the samples over two sequences.
// With a world among the lights, a tenth uniform (light_tables.cpp,
// mix_in_uniform: the world's cosine draws are the noisy ones).
enum class SelectionRule { Uniform, Power, Unoccluded, Tree, Defensive };

struct Technique {
    bool bsdf = false;  // cosine-weighted hemisphere
    SelectionRule selection = SelectionRule::Uniform;
    ShapeSampler sampler = ShapeSampler::SolidAngle;

    std::string name() const;
    bool operator==(const Technique& o) const {
        return bsdf == o.bsdf && (bsdf || (selection == o.selection && sampler == o.sampler));
    }
};

// "bsdf", "uniform/area", "power/solid-angle", "unoccluded/parallel", "tree/solid-angle",
// "uniform/projected-solid-angle", ...
std::optional<Technique> parse_technique(std::string_view name);

// Every technique name parse_technique accepts, `bsdf` first.
std::vector<std::string> technique_names();
// The same as a pattern for error messages: "bsdf, or <uniform|…>/<area|…>".
std::string technique_grammar();

}  // namespace omis
