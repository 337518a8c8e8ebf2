// The direct sum of the Plummer-softened inverse-square kernel, many targets
// against many sources, on structure-of-arrays data:
//
//   f_i += sum_j q_j K(t_i - p_j),   K(r) = r / (|r|^2 + eps^2)^(3/2)
//
// over the sources j whose group differs from the target's (a magnet's own
// poles do not act on it). A source at the target itself contributes nothing
// (r = 0 to rounding, i.e. s^2 = eps^2 exactly: the lanes test s^2 > eps^2, which
// also keeps 1/s^3 finite whatever the softening).
//
// This is the inner loop of both the direct summation and the tree's near
// field, so it is written for SIMD: the sources are swept eight (AVX-512) or
// four (AVX2) at a time, each lane with its own softened distance. The vector
// versions are compiled for their instruction sets with function attributes
// and chosen at run time from what the CPU reports, so a portable Release
// build (no -march) still runs the wide kernel where the hardware has it.
// The AVX-512 kernel takes 1/sqrt(s^2) from the hardware's 14-bit estimate and
// two Newton steps (relative error ~1e-16, as near to the rounded value as
// sqrt and a division, though not always the same bits); the AVX2 and scalar
// kernels use sqrt and a division. Results therefore depend, in the last
// bits, on the CPU: the bundled scenes never reach this kernel (their few
// poles take the scalar pair loop of pole_model.cpp), so their bits do not.
#pragma once

#include <cstddef>
#include <cstdint>

namespace alloy::multipole {

/// Sources as separate arrays (x, y, z, strength, group), all of length n.
/// Groups are doubles so that the lanes compare them with the coordinates'
/// width; a source in no group carries -1 and a target in none -2.
struct SoaSources {
  const double* x = nullptr;
  const double* y = nullptr;
  const double* z = nullptr;
  const double* q = nullptr;
  const double* g = nullptr;
  std::size_t n = 0;
};

/// Targets: positions, groups (as for SoaSources), and the sums they get.
struct SoaTargets {
  const double* x = nullptr;
  const double* y = nullptr;
  const double* z = nullptr;
  const double* g = nullptr;
  double* fx = nullptr;  ///< added to, not overwritten
  double* fy = nullptr;
  double* fz = nullptr;
  std::size_t n = 0;
};

/// Adds to every target the softened inverse-square sum over the sources not
/// in its group. `eps2` is the softening length squared.
void direct_accumulate(const SoaTargets& targets, const SoaSources& sources, double eps2);

/// Each pair once, both ways: every target gets the sum over the sources (as
/// direct_accumulate) and every source j gets, in (sfx, sfy, sfz)[j], the sum
/// over the targets of tq_i K(p_j - t_i) (the targets' own strengths `tq`).
/// Half the kernel evaluations of two direct_accumulate calls for two
/// disjoint sets (the FMM's near field between two leaves). Returns false (and
/// adds nothing) where this CPU has no wide kernel for it (AVX-512 only): the
/// caller then makes the two one-way calls, which are faster there.
bool direct_accumulate_mutual(const SoaTargets& targets, const double* tq,
                              const SoaSources& sources, double* sfx, double* sfy, double* sfz,
                              double eps2);
/// The same on the scalar reference loop (tests compare the two).
void direct_accumulate_mutual_scalar(const SoaTargets& targets, const double* tq,
                                     const SoaSources& sources, double* sfx, double* sfy,
                                     double* sfz, double eps2);

/// Sources in single precision, for the FMM's near field (fmm.hpp,
/// FmmOptions::single_near): coordinates relative to a point near them (so
/// that float keeps their separations to ~1e-7 of the region's size), groups
/// as integers (-1: none; a target in none carries -2).
struct SoaSourcesF {
  const float* x = nullptr;
  const float* y = nullptr;
  const float* z = nullptr;
  const float* q = nullptr;
  const std::int32_t* g = nullptr;
  std::size_t n = 0;
};
/// Targets in single precision (relative to the same point as the sources);
/// their sums are reduced per target and added to the double arrays.
struct SoaTargetsF {
  const float* x = nullptr;
  const float* y = nullptr;
  const float* z = nullptr;
  const std::int32_t* g = nullptr;
  double* fx = nullptr;  ///< added to, not overwritten
  double* fy = nullptr;
  double* fz = nullptr;
  std::size_t n = 0;
};

/// direct_accumulate and direct_accumulate_mutual in single precision,
/// sixteen sources a lane, 1/s from rsqrt14 and one Newton step (relative
/// error ~1e-8, below float's rounding): twice the lanes of the double
/// kernels. Each pair's relative error is about 1e-7 times the coordinates'
/// size over max(|r|, eps), so the caller keeps coordinates small against
/// the softening (fmm.cpp). A source within float rounding of its target
/// counts as at its position (left out). The source sums of the mutual one
/// go to float arrays (sfx, ...), added to. Return false (nothing added)
/// where the CPU has no AVX-512.
bool direct_accumulate_single(const SoaTargetsF& targets, const SoaSourcesF& sources, float eps2);
bool direct_accumulate_mutual_single(const SoaTargetsF& targets, const float* tq,
                                     const SoaSourcesF& sources, float* sfx, float* sfy, float* sfz,
                                     float eps2);

/// Which kernel direct_accumulate runs on this CPU: "avx512", "avx2" or "scalar".
const char* direct_kernel_isa();

/// The same with a named kernel ("avx512", "avx2", "scalar"), for tests that
/// compare them; false (and nothing added) if this CPU cannot run it.
bool direct_accumulate_with(const char* isa, const SoaTargets& targets, const SoaSources& sources,
                            double eps2);

}  // namespace alloy::multipole
