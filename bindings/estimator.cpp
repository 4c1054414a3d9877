// omis.combine: the generic MIS estimator over the C ABI.
#include "common.h"

namespace omis_py {
namespace {

py::object combine(const py::handle& f_in, const py::handle& pdfs_in,
                   const py::handle& technique_in, const py::handle& counts_in,
                   const std::string& strategy_name, const py::kwargs& options) {
    OMISStrategy strategy;
    if (!omisParseStrategy(c_string(strategy_name, "strategy"), &strategy))
        bad("strategy", "unknown strategy '" + strategy_name +
                            "' (balance, power, maximum, cutoff, optimal-direct, "
                            "optimal-progressive)");
    bool return_variance = false;
    std::vector<std::pair<std::string, double>> float_options;
    for (const auto& item : options) {
        const std::string key = py::str(item.first);
        if (key == "return_variance")
            return_variance = bool_arg(item.second, "return_variance");
        else if (key == "beta" || key == "cutoff")
            float_options.emplace_back(key, number_arg(item.second, key.c_str()));
        else
            throw py::type_error("combine() got an unexpected keyword argument '" + key + "'");
    }

    auto f = as_float_array(f_in, "f");
    auto pdfs = as_float_array(pdfs_in, "pdfs");
    auto technique = as_int_array(technique_in, "technique");
    auto counts = as_int_array(counts_in, "counts");

    if (f.ndim() != 1 && f.ndim() != 2) bad("f", "expected shape (S,) or (S, C), got " + shape_of(f));
    const py::ssize_t S = f.shape(0);
    const int C = f.ndim() == 2 ? int(f.shape(1)) : 1;
    if (C < 1 || C > 4) bad("f", "expected 1 to 4 channels, got " + std::to_string(C));
    if (S == 0) bad("f", "no samples");
    if (pdfs.ndim() != 2 || pdfs.shape(0) != S)
        bad("pdfs", "expected shape (" + std::to_string(S) + ", N), got " + shape_of(pdfs));
    const int N = int(pdfs.shape(1));
    if (N < 1 || N > OMIS_MAX_TECHNIQUES)
        bad("pdfs", "expected 1 to " + std::to_string(OMIS_MAX_TECHNIQUES) + " techniques, got " +
                        std::to_string(N));
    if (technique.ndim() != 1 || technique.shape(0) != S)
        bad("technique", "expected shape (" + std::to_string(S) + ",), got " + shape_of(technique));
    if (counts.ndim() != 1 || counts.shape(0) != N)
        bad("counts", "expected shape (" + std::to_string(N) + ",) to match pdfs, got " +
                          shape_of(counts));

    for (py::ssize_t i = 0; i < f.size(); ++i)
        if (!std::isfinite(f.data()[i])) bad("f", "contains NaN or Inf (flat index " + std::to_string(i) + ")");
    for (py::ssize_t i = 0; i < pdfs.size(); ++i) {
        const double p = pdfs.data()[i];
        if (!std::isfinite(p)) bad("pdfs", "contains NaN or Inf at sample " + std::to_string(i / N));
        if (p < 0) bad("pdfs", "negative density at sample " + std::to_string(i / N));
    }
    long long per_round = 0;
    for (int k = 0; k < N; ++k) {
        if (counts.data()[k] < 0) bad("counts", "entry " + std::to_string(k) + " is negative");
        per_round += counts.data()[k];
    }
    if (per_round == 0) bad("counts", "all zero: no technique is sampled");
    if (S % per_round != 0)
        bad("counts", "S = " + std::to_string(S) + " samples is not a whole number of rounds of " +
                          std::to_string(per_round) + " (sum of counts)");
    for (py::ssize_t s = 0; s < S; ++s) {
        const int t = technique.data()[s];
        if (t < 0 || t >= N)
            bad("technique", "sample " + std::to_string(s) + " names technique " +
                                 std::to_string(t) + ", outside [0, " + std::to_string(N) + ")");
        if (!(pdfs.data()[s * N + t] > 0))
            bad("pdfs", "sample " + std::to_string(s) + " has zero density under its own technique " +
                            std::to_string(t));
    }

    omis::capi::EstimatorRef estimator(omisNewEstimator(strategy, N, C, counts.data()));
    if (!estimator) raise_pending_error();
    for (const auto& [key, value] : float_options) {
        omisSetEstimatorFloat(estimator.get(), key.c_str(), value);
    }
    omisCommitEstimator(estimator.get());
    {
        const char* message = nullptr;
        if (omisGetError(&message) != OMIS_ERROR_NONE)
            bad(float_options.empty() ? "options" : float_options.front().first,
                message ? message : "invalid option");
    }

    py::array_t<double> estimate(C), variance(C);
    bool ok;
    {
        py::gil_scoped_release release;
        ok = omisAddEstimatorSamples(estimator.get(), size_t(S), technique.data(), sizeof(int),
                                     pdfs.data(), sizeof(double) * N, f.data(),
                                     sizeof(double) * C) &&
             omisGetEstimatorResult(estimator.get(), estimate.mutable_data(),
                                    variance.mutable_data());
    }
    if (!ok) raise_pending_error();
    if (return_variance) return py::make_tuple(estimate, variance);
    return std::move(estimate);
}

}  // namespace

void init_estimator(py::module_& m) {
    m.def("combine", &combine, py::arg("f"), py::arg("pdfs"), py::arg("technique"),
          py::arg("counts"), py::arg("strategy") = "optimal-direct",
          R"doc(Combines samples of N techniques with a MIS strategy (SPEC §6).

f: (S,) or (S, C) integrand values; pdfs: (S, N) densities of every technique at
every sample; technique: (S,) which technique drew each sample; counts: (N,)
samples of each technique per round, samples ordered round by round.
strategy: balance | power | maximum | cutoff | optimal-direct | optimal-progressive.
Options: beta (power), cutoff (cutoff), return_variance.
Returns (C,) estimates, or (estimates, variances) with return_variance=True.)doc");
}

}  // namespace omis_py
