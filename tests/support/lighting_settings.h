// Direct-lighting settings from technique names, as the tests and benchmarks
// write them.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "render/direct_lighting.h"
#include "render/effect_plan.h"
#include "render/techniques.h"

namespace omis::testing {

// names[k] drawn samples[k] times per round (SPEC §3); throws on an unknown name.
inline DirectLightingSettings lighting_settings(const std::vector<std::string>& names,
                                                const std::vector<int>& samples, int rounds,
                                                Strategy strategy, std::uint64_t seed) {
    DirectLightingSettings s;
    for (const auto& name : names) {
        const auto technique = parse_technique(name);
        if (!technique) throw std::invalid_argument("unknown technique '" + name + "'");
        s.techniques.push_back(*technique);
    }
    s.samples = samples;
    s.rounds = rounds;
    s.strategy = strategy;
    s.seed = seed;
    return s;
}

// The names of the techniques the effect plan chooses for `scene`, in order.
inline std::vector<std::string> plan_names(const Scene& scene) {
    std::vector<Technique> techniques;
    std::vector<int> samples;
    default_techniques(scene, techniques, samples);
    std::vector<std::string> names;
    for (const Technique& t : techniques) names.push_back(t.name());
    return names;
}

}  // namespace omis::testing
