#include "render/techniques.h"

namespace omis {

std::string Technique::name() const {
    if (bsdf) return "bsdf";
    const char* sel = selection == LightSelection::Uniform ? "uniform"
                      : selection == LightSelection::Power ? "power"
                      : selection == LightSelection::Tree  ? "tree"
                                                           : "unoccluded";
    return std::string(sel) + "/" + light_sampler_name(sampler);
}

std::optional<Technique> parse_technique(std::string_view name) {
    if (name == "bsdf") return Technique{true, {}, {}};
    const auto slash = name.find('/');
    if (slash == std::string_view::npos) return std::nullopt;
    const std::string_view sel = name.substr(0, slash), smp = name.substr(slash + 1);
    Technique t;
    if (sel == "uniform") t.selection = LightSelection::Uniform;
    else if (sel == "power") t.selection = LightSelection::Power;
    else if (sel == "unoccluded") t.selection = LightSelection::Unoccluded;
    else if (sel == "tree") t.selection = LightSelection::Tree;
    else return std::nullopt;
    if (smp == "area") t.sampler = LightSampler::Area;
    else if (smp == "solid-angle") t.sampler = LightSampler::SolidAngle;
    else if (smp == "parallel") t.sampler = LightSampler::Parallel;
    else if (smp == "projected-solid-angle") t.sampler = LightSampler::ProjectedSolidAngle;
    else return std::nullopt;
    return t;
}

}  // namespace omis
