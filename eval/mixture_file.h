// The Gaussian-mixture stand-in (recon/track/gaussian_mixture_flow.h) as an .npz
// file, the form tools/velocity_server.py reads:
//   weights (F, K) f8 (0 marks an unused mode slot), means (F, K, D) f8,
//   sigmas (F, K) f8, shape_dim () i8.
#pragma once

#include <filesystem>

#include "recon/track/gaussian_mixture_flow.h"

namespace doasido::recon {

void WriteMixtureNpz(const std::filesystem::path& path, const GaussianMixtureFlow& model);

// Throws Error("bad_bundle") naming the file and key for missing keys or
// wrong shapes, Error("bad_model") for a mixture the model refuses.
GaussianMixtureFlow ReadMixtureNpz(const std::filesystem::path& path);

}  // namespace doasido::recon
