// C ABI of the MIS estimator (omis.h, "MIS estimator").
#include <memory>
#include <vector>

#include "api_common.h"
#include "mis/estimator.h"

using namespace omis::api;

struct OMISEstimatorImpl : Tagged<0x54534545> {  // "EEST"
    omis::Strategy strategy;
    int num_techniques, num_channels;
    std::vector<int> counts;
    omis::StrategyOptions options;
    std::unique_ptr<omis::MisEstimator> estimator;  // set by commit

    omis::MisEstimator& committed() {
        if (!estimator)
            throw ApiError(OMIS_ERROR_INVALID_OPERATION,
                           "estimator: not committed (call omisCommitEstimator first)");
        return *estimator;
    }
};

omis::Strategy omis::api::to_core(const OMISStrategy& strategy) {
    const int s = enum_value(strategy);
    switch (s) {
        case OMIS_STRATEGY_BALANCE: return omis::Strategy::Balance;
        case OMIS_STRATEGY_POWER: return omis::Strategy::Power;
        case OMIS_STRATEGY_MAXIMUM: return omis::Strategy::Maximum;
        case OMIS_STRATEGY_CUTOFF: return omis::Strategy::Cutoff;
        case OMIS_STRATEGY_OPTIMAL_DIRECT: return omis::Strategy::OptimalDirect;
        case OMIS_STRATEGY_OPTIMAL_PROGRESSIVE: return omis::Strategy::OptimalProgressive;
    }
    throw std::invalid_argument("strategy: unknown value " + std::to_string(s));
}

OMIS_API bool omisParseStrategy(const char* name, OMISStrategy* strategy) {
    return guarded(false, [&] {
        checked(strategy, "strategy");
        const auto parsed = omis::parse_strategy(checked(name, "name"));
        if (!parsed) return false;
        static const OMISStrategy table[] = {
            OMIS_STRATEGY_BALANCE,        OMIS_STRATEGY_POWER,
            OMIS_STRATEGY_MAXIMUM,        OMIS_STRATEGY_CUTOFF,
            OMIS_STRATEGY_OPTIMAL_DIRECT, OMIS_STRATEGY_OPTIMAL_PROGRESSIVE};
        *strategy = table[int(*parsed)];
        return true;
    });
}

OMIS_API OMISEstimator omisNewEstimator(OMISStrategy strategy, int numTechniques,
                                        int numChannels, const int* counts) {
    return guarded<OMISEstimator>(nullptr, [&] {
        checked(counts, "counts");
        auto impl = std::make_unique<OMISEstimatorImpl>();
        impl->strategy = to_core(strategy);
        if (numTechniques < 1 || numTechniques > omis::kMaxMisTechniques)
            throw std::invalid_argument("numTechniques: must be 1 to 32");
        impl->num_techniques = numTechniques;
        impl->num_channels = numChannels;
        impl->counts.assign(counts, counts + numTechniques);
        // Validate sizes now so the error comes from the call that caused it.
        omis::MisEstimator probe(impl->strategy, numTechniques, numChannels, impl->counts);
        return impl.release();
    });
}

OMIS_API void omisRetainEstimator(OMISEstimator estimator) {
    retain_handle(estimator, "estimator");
}

OMIS_API void omisReleaseEstimator(OMISEstimator estimator) {
    release_handle(estimator, "estimator");
}

OMIS_API void omisSetEstimatorFloat(OMISEstimator estimator, const char* name, double value) {
    guarded_void([&] {
        auto* e = checked(estimator, "estimator");
        const std::string key = checked(name, "name");
        if (e->estimator)
            throw ApiError(OMIS_ERROR_INVALID_OPERATION,
                           "estimator: options cannot change after commit");
        if (key == "beta")
            e->options.beta = value;
        else if (key == "cutoff")
            e->options.cutoff = value;
        else
            throw std::invalid_argument("name: unknown estimator option '" + key + "'");
    });
}

OMIS_API void omisCommitEstimator(OMISEstimator estimator) {
    guarded_void([&] {
        auto* e = checked(estimator, "estimator");
        if (e->estimator)
            throw ApiError(OMIS_ERROR_INVALID_OPERATION,
                           "estimator: already committed (a second commit would drop its "
                           "samples; omisResetEstimator starts again)");
        e->estimator = std::make_unique<omis::MisEstimator>(
            e->strategy, e->num_techniques, e->num_channels, e->counts, e->options);
    });
}

OMIS_API bool omisAddEstimatorSamples(OMISEstimator estimator, size_t count,
                                      const int* technique, size_t techniqueStride,
                                      const double* pdfs, size_t pdfStride,
                                      const double* f, size_t fStride) {
    return guarded(false, [&] {
        auto& e = checked(estimator, "estimator")->committed();
        if (count == 0) return true;
        e.add_samples(count, checked(technique, "technique"), techniqueStride,
                      checked(pdfs, "pdfs"), pdfStride, checked(f, "f"), fStride);
        return true;
    });
}

OMIS_API bool omisGetEstimatorResult(OMISEstimator estimator, double* estimate,
                                     double* variance) {
    return guarded(false, [&] {
        auto& e = checked(estimator, "estimator")->committed();
        checked(estimate, "estimate");
        const omis::MisResult r = e.result();
        for (int c = 0; c < e.num_channels(); ++c) {
            estimate[c] = r.estimate[c];
            if (variance) variance[c] = r.variance[c];
        }
        return true;
    });
}

OMIS_API void omisResetEstimator(OMISEstimator estimator) {
    guarded_void([&] { checked(estimator, "estimator")->committed().reset(); });
}
