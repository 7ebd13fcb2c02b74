#include "eval/mixture_file.h"

#include <algorithm>

#include "recon/bundle/npy.h"

namespace doasido::recon {

void WriteMixtureNpz(const std::filesystem::path& path, const GaussianMixtureFlow& model) {
  const std::int64_t F = model.frames(), D = model.Layout().dim();
  std::int64_t K = 0;
  for (int f = 0; f < F; ++f) K = std::max<std::int64_t>(K, model.mixture(f).size());
  std::vector<double> weights(F * K, 0.0), sigmas(F * K, 1.0), means(F * K * D, 0.0);
  for (int f = 0; f < F; ++f) {
    const Mixture& m = model.mixture(f);
    for (size_t k = 0; k < m.size(); ++k) {
      weights[f * K + k] = m[k].weight;
      sigmas[f * K + k] = m[k].sigma;
      std::copy(m[k].mean.data(), m[k].mean.data() + D, means.begin() + (f * K + k) * D);
    }
  }
  WriteNpz(path, {{"weights", MakeArray({F, K}, weights)},
                  {"means", MakeArray({F, K, D}, means)},
                  {"sigmas", MakeArray({F, K}, sigmas)},
                  {"shape_dim", MakeArray<std::int64_t>({}, {model.Layout().shape_dim})}});
}

GaussianMixtureFlow ReadMixtureNpz(const std::filesystem::path& path) {
  const std::string file = path.string();
  const NpzArchive npz = ReadNpz(path);
  const NpyArray& weights = RequireKey(npz, "weights", file);
  CheckShape(weights, {-1, -1}, file, "weights");
  const std::int64_t F = weights.shape[0], K = weights.shape[1];
  const NpyArray& means = RequireKey(npz, "means", file);
  CheckShape(means, {F, K, -1}, file, "means");
  const NpyArray& sigmas = RequireKey(npz, "sigmas", file);
  CheckShape(sigmas, {F, K}, file, "sigmas");
  const NpyArray& shape_dim = RequireKey(npz, "shape_dim", file);
  CheckInteger(shape_dim, file, "shape_dim");
  for (const auto* a : {&weights, &means, &sigmas}) {
    CheckFloat(*a, file, a == &weights ? "weights" : a == &means ? "means" : "sigmas");
  }
  const std::int64_t D = means.shape[2];
  const FlowLayout layout{.shape_dim = static_cast<int>(shape_dim.AsInt(0))};
  std::vector<Mixture> frames(F);
  for (std::int64_t f = 0; f < F; ++f) {
    for (std::int64_t k = 0; k < K; ++k) {
      const double w = weights.AsDouble(f * K + k);
      if (w == 0) continue;
      MixtureMode mode{w, Eigen::VectorXd(D), sigmas.AsDouble(f * K + k)};
      for (std::int64_t d = 0; d < D; ++d) mode.mean[d] = means.AsDouble((f * K + k) * D + d);
      frames[f].push_back(std::move(mode));
    }
  }
  return GaussianMixtureFlow(layout, std::move(frames));
}

}  // namespace doasido::recon
