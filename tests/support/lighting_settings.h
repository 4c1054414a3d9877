// Direct-lighting settings from technique names, as the tests and benchmarks
// write them.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "render/direct_lighting.h"
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

}  // namespace omis::testing
