#include "render/techniques.h"

#include <utility>

namespace omis {

namespace {

// The one table of selection and sampler names (SPEC §3); parsing, printing
// and technique_names() all read it.
constexpr std::pair<SelectionRule, const char*> kSelections[] = {
    {SelectionRule::Uniform, "uniform"},
    {SelectionRule::Power, "power"},
    {SelectionRule::Unoccluded, "unoccluded"},
    {SelectionRule::Tree, "tree"},
    {SelectionRule::Defensive, "defensive"},
};
constexpr ShapeSampler kSamplers[] = {ShapeSampler::Area, ShapeSampler::SolidAngle,
                                      ShapeSampler::Parallel, ShapeSampler::ProjectedSolidAngle};

}  // namespace

std::string Technique::name() const {
    if (bsdf) return "bsdf";
    for (const auto& [selection_, name] : kSelections)
        if (selection_ == selection) return std::string(name) + "/" + shape_sampler_name(sampler);
    return "unknown";
}

std::optional<Technique> parse_technique(std::string_view name) {
    if (name == "bsdf") return Technique{true, {}, {}};
    const auto slash = name.find('/');
    if (slash == std::string_view::npos) return std::nullopt;
    const std::string_view selection = name.substr(0, slash), sampler = name.substr(slash + 1);
    Technique t;
    bool known_selection = false, known_sampler = false;
    for (const auto& [value, text] : kSelections)
        if (selection == text) {
            t.selection = value;
            known_selection = true;
        }
    for (ShapeSampler value : kSamplers)
        if (sampler == shape_sampler_name(value)) {
            t.sampler = value;
            known_sampler = true;
        }
    if (!known_selection || !known_sampler) return std::nullopt;
    return t;
}

std::string technique_grammar() {
    std::string selections, samplers;
    for (const auto& [value, text] : kSelections) selections += (selections.empty() ? "" : "|") + std::string(text);
    for (ShapeSampler value : kSamplers)
        samplers += (samplers.empty() ? "" : "|") + std::string(shape_sampler_name(value));
    return "bsdf, or <" + selections + ">/<" + samplers + ">";
}

std::vector<std::string> technique_names() {
    std::vector<std::string> names{"bsdf"};
    for (const auto& [selection, text] : kSelections)
        for (ShapeSampler sampler : kSamplers)
            names.push_back(std::string(text) + "/" + shape_sampler_name(sampler));
    return names;
}

}  // namespace omis
