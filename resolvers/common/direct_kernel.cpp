#include "resolvers/common/direct_kernel.hpp"

#include <cmath>
#include <string_view>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define ALLOY_DIRECT_KERNEL_X86 1
// GCC 12's AVX-512 headers start some intrinsics from _mm512_undefined_pd(),
// which -Wmaybe-uninitialized reports; and passing vectors between functions
// compiled for different targets draws -Wpsabi. Neither is a fault here (the
// vector functions are only called through the dispatch below).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wpsabi"
#endif
#endif

namespace alloy::multipole {

namespace {

// The reference: one pair at a time, sqrt and a division.
void accumulate_scalar(const SoaTargets& t, const SoaSources& s, double eps2) {
  for (std::size_t i = 0; i < t.n; ++i) {
    const double x = t.x[i], y = t.y[i], z = t.z[i], g = t.g[i];
    double ax = 0, ay = 0, az = 0;
    for (std::size_t j = 0; j < s.n; ++j) {
      const double dx = x - s.x[j], dy = y - s.y[j], dz = z - s.z[j];
      const double s2 = dx * dx + dy * dy + dz * dz + eps2;
      if (s.g[j] == g || !(s2 > eps2)) continue;
      const double w = s.q[j] / (s2 * std::sqrt(s2));
      ax += w * dx, ay += w * dy, az += w * dz;
    }
    t.fx[i] += ax, t.fy[i] += ay, t.fz[i] += az;
  }
}

// Each pair once: the target's sum in registers, the source's in memory.
void mutual_scalar(const SoaTargets& t, const double* tq, const SoaSources& s, double* sfx,
                   double* sfy, double* sfz, double eps2) {
  for (std::size_t i = 0; i < t.n; ++i) {
    const double x = t.x[i], y = t.y[i], z = t.z[i], g = t.g[i], q = tq[i];
    double ax = 0, ay = 0, az = 0;
    for (std::size_t j = 0; j < s.n; ++j) {
      const double dx = x - s.x[j], dy = y - s.y[j], dz = z - s.z[j];
      const double s2 = dx * dx + dy * dy + dz * dz + eps2;
      if (s.g[j] == g || !(s2 > eps2)) continue;
      const double w = 1.0 / (s2 * std::sqrt(s2));
      const double ws = s.q[j] * w, wt = q * w;
      ax += ws * dx, ay += ws * dy, az += ws * dz;
      sfx[j] -= wt * dx, sfy[j] -= wt * dy, sfz[j] -= wt * dz;
    }
    t.fx[i] += ax, t.fy[i] += ay, t.fz[i] += az;
  }
}

#ifdef ALLOY_DIRECT_KERNEL_X86

// Each pair once, eight sources a lane: 1/s^3 as in lane512 below. Two
// targets share each load of the sources and each load and store of the
// sources' sums (the stores are what the one-way kernel does not have).
__attribute__((target("avx512f"), always_inline)) inline __m512d inv_cube512(__m512d s2) {
  const __m512d half = _mm512_set1_pd(0.5), three_halves = _mm512_set1_pd(1.5);
  __m512d r = _mm512_rsqrt14_pd(s2);
  const __m512d h = _mm512_mul_pd(half, s2);
  r = _mm512_mul_pd(r, _mm512_fnmadd_pd(h, _mm512_mul_pd(r, r), three_halves));
  r = _mm512_mul_pd(r, _mm512_fnmadd_pd(h, _mm512_mul_pd(r, r), three_halves));
  return _mm512_mul_pd(r, _mm512_mul_pd(r, r));
}

__attribute__((target("avx512f"))) void mutual_avx512(const SoaTargets& t, const double* tq,
                                                      const SoaSources& s, double* sfx, double* sfy,
                                                      double* sfz, double eps2) {
  const __m512d e2 = _mm512_set1_pd(eps2), zero = _mm512_setzero_pd(), one = _mm512_set1_pd(1.0);
  const std::size_t n = s.n;
  std::size_t i = 0;
  for (; i < t.n; i += 2) {
    // An odd last target pairs with itself at strength 0 and sums dropped.
    const std::size_t i1 = i + 1 < t.n ? i + 1 : i;
    const __m512d x0 = _mm512_set1_pd(t.x[i]), y0 = _mm512_set1_pd(t.y[i]),
                  z0 = _mm512_set1_pd(t.z[i]), g0 = _mm512_set1_pd(t.g[i]),
                  q0 = _mm512_set1_pd(tq[i]);
    const __m512d x1 = _mm512_set1_pd(t.x[i1]), y1 = _mm512_set1_pd(t.y[i1]),
                  z1 = _mm512_set1_pd(t.z[i1]), g1 = _mm512_set1_pd(t.g[i1]),
                  q1 = _mm512_set1_pd(i1 != i ? tq[i1] : 0.0);
    __m512d ax0 = zero, ay0 = zero, az0 = zero, ax1 = zero, ay1 = zero, az1 = zero;
    for (std::size_t j = 0; j < n; j += 8) {
      const __mmask8 valid = n - j >= 8 ? __mmask8(0xff) : __mmask8((1u << (n - j)) - 1);
      const __m512d sx = _mm512_maskz_loadu_pd(valid, s.x + j),
                    sy = _mm512_maskz_loadu_pd(valid, s.y + j),
                    sz = _mm512_maskz_loadu_pd(valid, s.z + j),
                    sq = _mm512_maskz_loadu_pd(valid, s.q + j),
                    sg = _mm512_maskz_loadu_pd(valid, s.g + j);
      const __m512d dx0 = _mm512_sub_pd(x0, sx), dy0 = _mm512_sub_pd(y0, sy),
                    dz0 = _mm512_sub_pd(z0, sz);
      const __m512d dx1 = _mm512_sub_pd(x1, sx), dy1 = _mm512_sub_pd(y1, sy),
                    dz1 = _mm512_sub_pd(z1, sz);
      __m512d s20 =
          _mm512_fmadd_pd(dx0, dx0, _mm512_fmadd_pd(dy0, dy0, _mm512_fmadd_pd(dz0, dz0, e2)));
      __m512d s21 =
          _mm512_fmadd_pd(dx1, dx1, _mm512_fmadd_pd(dy1, dy1, _mm512_fmadd_pd(dz1, dz1, e2)));
      const __mmask8 keep0 =
          valid & _mm512_cmp_pd_mask(g0, sg, _CMP_NEQ_UQ) & _mm512_cmp_pd_mask(s20, e2, _CMP_GT_OQ);
      const __mmask8 keep1 =
          valid & _mm512_cmp_pd_mask(g1, sg, _CMP_NEQ_UQ) & _mm512_cmp_pd_mask(s21, e2, _CMP_GT_OQ);
      s20 = _mm512_mask_blend_pd(keep0, one, s20);
      s21 = _mm512_mask_blend_pd(keep1, one, s21);
      const __m512d w0 = _mm512_maskz_mov_pd(keep0, inv_cube512(s20)),
                    w1 = _mm512_maskz_mov_pd(keep1, inv_cube512(s21));
      const __m512d ws0 = _mm512_mul_pd(w0, sq), ws1 = _mm512_mul_pd(w1, sq);
      ax0 = _mm512_fmadd_pd(ws0, dx0, ax0), ay0 = _mm512_fmadd_pd(ws0, dy0, ay0),
      az0 = _mm512_fmadd_pd(ws0, dz0, az0);
      ax1 = _mm512_fmadd_pd(ws1, dx1, ax1), ay1 = _mm512_fmadd_pd(ws1, dy1, ay1),
      az1 = _mm512_fmadd_pd(ws1, dz1, az1);
      const __m512d wt0 = _mm512_mul_pd(w0, q0), wt1 = _mm512_mul_pd(w1, q1);
      // The sources' sums: minus both targets' pulls, the first then the second.
      _mm512_mask_storeu_pd(
          sfx + j, valid,
          _mm512_fnmadd_pd(wt1, dx1,
                           _mm512_fnmadd_pd(wt0, dx0, _mm512_maskz_loadu_pd(valid, sfx + j))));
      _mm512_mask_storeu_pd(
          sfy + j, valid,
          _mm512_fnmadd_pd(wt1, dy1,
                           _mm512_fnmadd_pd(wt0, dy0, _mm512_maskz_loadu_pd(valid, sfy + j))));
      _mm512_mask_storeu_pd(
          sfz + j, valid,
          _mm512_fnmadd_pd(wt1, dz1,
                           _mm512_fnmadd_pd(wt0, dz0, _mm512_maskz_loadu_pd(valid, sfz + j))));
    }
    t.fx[i] += _mm512_reduce_add_pd(ax0), t.fy[i] += _mm512_reduce_add_pd(ay0),
        t.fz[i] += _mm512_reduce_add_pd(az0);
    if (i1 != i)
      t.fx[i1] += _mm512_reduce_add_pd(ax1), t.fy[i1] += _mm512_reduce_add_pd(ay1),
          t.fz[i1] += _mm512_reduce_add_pd(az1);
  }
}

// Eight sources a lane each. 1/s from rsqrt14 (|rel. error| < 2^-14) and two
// Newton steps y <- y (3 - s^2 y^2) / 2, which square the error each time
// (2^-28, then below double rounding). Excluded lanes (own group, or r = 0)
// get strength 0 and a harmless s^2 of 1, so no inf or NaN is ever formed.
// Two targets share each load of the sources.
__attribute__((target("avx512f"), always_inline)) inline void lane512(
    __m512d x, __m512d y, __m512d z, __m512d g, __m512d sx, __m512d sy, __m512d sz, __m512d sq,
    __m512d sg, __mmask8 valid, __m512d e2, __m512d& ax, __m512d& ay, __m512d& az) {
  const __m512d half = _mm512_set1_pd(0.5), three_halves = _mm512_set1_pd(1.5),
                one = _mm512_set1_pd(1.0);
  const __m512d dx = _mm512_sub_pd(x, sx), dy = _mm512_sub_pd(y, sy), dz = _mm512_sub_pd(z, sz);
  __m512d s2 = _mm512_fmadd_pd(dx, dx, _mm512_fmadd_pd(dy, dy, _mm512_fmadd_pd(dz, dz, e2)));
  // s^2 > eps^2: a source at the target itself (r = 0, to rounding) is left
  // out, which also keeps 1/s^3 finite for any softening.
  const __mmask8 keep =
      valid & _mm512_cmp_pd_mask(g, sg, _CMP_NEQ_UQ) & _mm512_cmp_pd_mask(s2, e2, _CMP_GT_OQ);
  s2 = _mm512_mask_blend_pd(keep, one, s2);
  __m512d r = _mm512_rsqrt14_pd(s2);
  const __m512d h = _mm512_mul_pd(half, s2);
  r = _mm512_mul_pd(r, _mm512_fnmadd_pd(h, _mm512_mul_pd(r, r), three_halves));
  r = _mm512_mul_pd(r, _mm512_fnmadd_pd(h, _mm512_mul_pd(r, r), three_halves));
  const __m512d w = _mm512_maskz_mul_pd(keep, sq, _mm512_mul_pd(r, _mm512_mul_pd(r, r)));
  ax = _mm512_fmadd_pd(w, dx, ax);
  ay = _mm512_fmadd_pd(w, dy, ay);
  az = _mm512_fmadd_pd(w, dz, az);
}

__attribute__((target("avx512f"))) void accumulate_avx512(const SoaTargets& t, const SoaSources& s,
                                                          double eps2) {
  const __m512d e2 = _mm512_set1_pd(eps2), zero = _mm512_setzero_pd();
  const std::size_t n = s.n;
  std::size_t i = 0;
  for (; i + 2 <= t.n; i += 2) {
    const __m512d x0 = _mm512_set1_pd(t.x[i]), y0 = _mm512_set1_pd(t.y[i]),
                  z0 = _mm512_set1_pd(t.z[i]), g0 = _mm512_set1_pd(t.g[i]);
    const __m512d x1 = _mm512_set1_pd(t.x[i + 1]), y1 = _mm512_set1_pd(t.y[i + 1]),
                  z1 = _mm512_set1_pd(t.z[i + 1]), g1 = _mm512_set1_pd(t.g[i + 1]);
    __m512d ax0 = zero, ay0 = zero, az0 = zero, ax1 = zero, ay1 = zero, az1 = zero;
    for (std::size_t j = 0; j < n; j += 8) {
      const __mmask8 valid = n - j >= 8 ? __mmask8(0xff) : __mmask8((1u << (n - j)) - 1);
      const __m512d sx = _mm512_maskz_loadu_pd(valid, s.x + j),
                    sy = _mm512_maskz_loadu_pd(valid, s.y + j),
                    sz = _mm512_maskz_loadu_pd(valid, s.z + j),
                    sq = _mm512_maskz_loadu_pd(valid, s.q + j),
                    sg = _mm512_maskz_loadu_pd(valid, s.g + j);
      lane512(x0, y0, z0, g0, sx, sy, sz, sq, sg, valid, e2, ax0, ay0, az0);
      lane512(x1, y1, z1, g1, sx, sy, sz, sq, sg, valid, e2, ax1, ay1, az1);
    }
    t.fx[i] += _mm512_reduce_add_pd(ax0), t.fy[i] += _mm512_reduce_add_pd(ay0),
        t.fz[i] += _mm512_reduce_add_pd(az0);
    t.fx[i + 1] += _mm512_reduce_add_pd(ax1), t.fy[i + 1] += _mm512_reduce_add_pd(ay1),
        t.fz[i + 1] += _mm512_reduce_add_pd(az1);
  }
  for (; i < t.n; ++i) {
    const __m512d x0 = _mm512_set1_pd(t.x[i]), y0 = _mm512_set1_pd(t.y[i]),
                  z0 = _mm512_set1_pd(t.z[i]), g0 = _mm512_set1_pd(t.g[i]);
    __m512d ax0 = zero, ay0 = zero, az0 = zero;
    for (std::size_t j = 0; j < n; j += 8) {
      const __mmask8 valid = n - j >= 8 ? __mmask8(0xff) : __mmask8((1u << (n - j)) - 1);
      lane512(x0, y0, z0, g0, _mm512_maskz_loadu_pd(valid, s.x + j),
              _mm512_maskz_loadu_pd(valid, s.y + j), _mm512_maskz_loadu_pd(valid, s.z + j),
              _mm512_maskz_loadu_pd(valid, s.q + j), _mm512_maskz_loadu_pd(valid, s.g + j), valid,
              e2, ax0, ay0, az0);
    }
    t.fx[i] += _mm512_reduce_add_pd(ax0), t.fy[i] += _mm512_reduce_add_pd(ay0),
        t.fz[i] += _mm512_reduce_add_pd(az0);
  }
}

// --- single precision (the FMM's near field) ------------------------------------
// Sixteen sources a lane, two targets per sweep; MUTUAL also subtracts each
// pair's pull from the source's sums (in memory). 1/s from rsqrt14 and one
// Newton step: (2^-14)^2 * 3/2, under float's 2^-24.
template <bool MUTUAL>
__attribute__((target("avx512f"), always_inline)) inline void sweep_f32(const SoaTargetsF& t,
                                                                        const float* tq,
                                                                        const SoaSourcesF& s,
                                                                        float* sfx, float* sfy,
                                                                        float* sfz, float eps2) {
  const __m512 e2 = _mm512_set1_ps(eps2), zero = _mm512_setzero_ps(), one = _mm512_set1_ps(1.0f),
               half = _mm512_set1_ps(0.5f), three_halves = _mm512_set1_ps(1.5f);
  const std::size_t n = s.n;
  for (std::size_t i = 0; i < t.n; i += 2) {
    // An odd last target pairs with itself at strength 0 and sums dropped.
    const std::size_t i1 = i + 1 < t.n ? i + 1 : i;
    const __m512 x0 = _mm512_set1_ps(t.x[i]), y0 = _mm512_set1_ps(t.y[i]),
                 z0 = _mm512_set1_ps(t.z[i]), x1 = _mm512_set1_ps(t.x[i1]),
                 y1 = _mm512_set1_ps(t.y[i1]), z1 = _mm512_set1_ps(t.z[i1]);
    const __m512i g0 = _mm512_set1_epi32(t.g[i]), g1 = _mm512_set1_epi32(t.g[i1]);
    __m512 q0 = zero, q1 = zero;
    if constexpr (MUTUAL) q0 = _mm512_set1_ps(tq[i]), q1 = _mm512_set1_ps(i1 != i ? tq[i1] : 0.0f);
    __m512 ax0 = zero, ay0 = zero, az0 = zero, ax1 = zero, ay1 = zero, az1 = zero;
    for (std::size_t j = 0; j < n; j += 16) {
      const __mmask16 valid = n - j >= 16 ? __mmask16(0xffff) : __mmask16((1u << (n - j)) - 1);
      const __m512 sx = _mm512_maskz_loadu_ps(valid, s.x + j),
                   sy = _mm512_maskz_loadu_ps(valid, s.y + j),
                   sz = _mm512_maskz_loadu_ps(valid, s.z + j),
                   sq = _mm512_maskz_loadu_ps(valid, s.q + j);
      const __m512i sg = _mm512_maskz_loadu_epi32(valid, s.g + j);
      const __m512 dx0 = _mm512_sub_ps(x0, sx), dy0 = _mm512_sub_ps(y0, sy),
                   dz0 = _mm512_sub_ps(z0, sz), dx1 = _mm512_sub_ps(x1, sx),
                   dy1 = _mm512_sub_ps(y1, sy), dz1 = _mm512_sub_ps(z1, sz);
      __m512 s20 =
          _mm512_fmadd_ps(dx0, dx0, _mm512_fmadd_ps(dy0, dy0, _mm512_fmadd_ps(dz0, dz0, e2)));
      __m512 s21 =
          _mm512_fmadd_ps(dx1, dx1, _mm512_fmadd_ps(dy1, dy1, _mm512_fmadd_ps(dz1, dz1, e2)));
      const __mmask16 keep0 =
          valid & _mm512_cmpneq_epi32_mask(g0, sg) & _mm512_cmp_ps_mask(s20, e2, _CMP_GT_OQ);
      const __mmask16 keep1 =
          valid & _mm512_cmpneq_epi32_mask(g1, sg) & _mm512_cmp_ps_mask(s21, e2, _CMP_GT_OQ);
      s20 = _mm512_mask_blend_ps(keep0, one, s20);
      s21 = _mm512_mask_blend_ps(keep1, one, s21);
      __m512 r0 = _mm512_rsqrt14_ps(s20), r1 = _mm512_rsqrt14_ps(s21);
      r0 = _mm512_mul_ps(
          r0, _mm512_fnmadd_ps(_mm512_mul_ps(half, s20), _mm512_mul_ps(r0, r0), three_halves));
      r1 = _mm512_mul_ps(
          r1, _mm512_fnmadd_ps(_mm512_mul_ps(half, s21), _mm512_mul_ps(r1, r1), three_halves));
      const __m512 w0 = _mm512_maskz_mul_ps(keep0, r0, _mm512_mul_ps(r0, r0)),
                   w1 = _mm512_maskz_mul_ps(keep1, r1, _mm512_mul_ps(r1, r1));
      const __m512 ws0 = _mm512_mul_ps(w0, sq), ws1 = _mm512_mul_ps(w1, sq);
      ax0 = _mm512_fmadd_ps(ws0, dx0, ax0), ay0 = _mm512_fmadd_ps(ws0, dy0, ay0),
      az0 = _mm512_fmadd_ps(ws0, dz0, az0);
      ax1 = _mm512_fmadd_ps(ws1, dx1, ax1), ay1 = _mm512_fmadd_ps(ws1, dy1, ay1),
      az1 = _mm512_fmadd_ps(ws1, dz1, az1);
      if constexpr (MUTUAL) {
        const __m512 wt0 = _mm512_mul_ps(w0, q0), wt1 = _mm512_mul_ps(w1, q1);
        _mm512_mask_storeu_ps(
            sfx + j, valid,
            _mm512_fnmadd_ps(wt1, dx1,
                             _mm512_fnmadd_ps(wt0, dx0, _mm512_maskz_loadu_ps(valid, sfx + j))));
        _mm512_mask_storeu_ps(
            sfy + j, valid,
            _mm512_fnmadd_ps(wt1, dy1,
                             _mm512_fnmadd_ps(wt0, dy0, _mm512_maskz_loadu_ps(valid, sfy + j))));
        _mm512_mask_storeu_ps(
            sfz + j, valid,
            _mm512_fnmadd_ps(wt1, dz1,
                             _mm512_fnmadd_ps(wt0, dz0, _mm512_maskz_loadu_ps(valid, sfz + j))));
      }
    }
    t.fx[i] += double(_mm512_reduce_add_ps(ax0)), t.fy[i] += double(_mm512_reduce_add_ps(ay0)),
        t.fz[i] += double(_mm512_reduce_add_ps(az0));
    if (i1 != i)
      t.fx[i1] += double(_mm512_reduce_add_ps(ax1)), t.fy[i1] += double(_mm512_reduce_add_ps(ay1)),
          t.fz[i1] += double(_mm512_reduce_add_ps(az1));
  }
}

__attribute__((target("avx512f"))) void accumulate_f32(const SoaTargetsF& t, const SoaSourcesF& s,
                                                       float eps2) {
  sweep_f32<false>(t, nullptr, s, nullptr, nullptr, nullptr, eps2);
}
__attribute__((target("avx512f"))) void mutual_f32(const SoaTargetsF& t, const float* tq,
                                                   const SoaSourcesF& s, float* sfx, float* sfy,
                                                   float* sfz, float eps2) {
  sweep_f32<true>(t, tq, s, sfx, sfy, sfz, eps2);
}

// Four sources a lane each, with the IEEE sqrt and division (AVX2 has no
// double-precision reciprocal square root estimate); the tail by the scalar
// loop.
__attribute__((target("avx2,fma"))) void accumulate_avx2(const SoaTargets& t, const SoaSources& s,
                                                         double eps2) {
  const __m256d e2 = _mm256_set1_pd(eps2), one = _mm256_set1_pd(1.0), zero = _mm256_setzero_pd();
  const std::size_t n4 = s.n & ~std::size_t(3);
  for (std::size_t i = 0; i < t.n; ++i) {
    const __m256d x = _mm256_set1_pd(t.x[i]), y = _mm256_set1_pd(t.y[i]),
                  z = _mm256_set1_pd(t.z[i]), g = _mm256_set1_pd(t.g[i]);
    __m256d ax = zero, ay = zero, az = zero;
    for (std::size_t j = 0; j < n4; j += 4) {
      const __m256d dx = _mm256_sub_pd(x, _mm256_loadu_pd(s.x + j)),
                    dy = _mm256_sub_pd(y, _mm256_loadu_pd(s.y + j)),
                    dz = _mm256_sub_pd(z, _mm256_loadu_pd(s.z + j));
      __m256d s2 = _mm256_fmadd_pd(dx, dx, _mm256_fmadd_pd(dy, dy, _mm256_fmadd_pd(dz, dz, e2)));
      const __m256d keep = _mm256_and_pd(_mm256_cmp_pd(g, _mm256_loadu_pd(s.g + j), _CMP_NEQ_UQ),
                                         _mm256_cmp_pd(s2, e2, _CMP_GT_OQ));
      s2 = _mm256_blendv_pd(one, s2, keep);
      const __m256d w = _mm256_and_pd(
          keep, _mm256_div_pd(_mm256_loadu_pd(s.q + j), _mm256_mul_pd(s2, _mm256_sqrt_pd(s2))));
      ax = _mm256_fmadd_pd(w, dx, ax);
      ay = _mm256_fmadd_pd(w, dy, ay);
      az = _mm256_fmadd_pd(w, dz, az);
    }
    alignas(32) double bx[4], by[4], bz[4];
    _mm256_store_pd(bx, ax), _mm256_store_pd(by, ay), _mm256_store_pd(bz, az);
    t.fx[i] += (bx[0] + bx[1]) + (bx[2] + bx[3]);
    t.fy[i] += (by[0] + by[1]) + (by[2] + by[3]);
    t.fz[i] += (bz[0] + bz[1]) + (bz[2] + bz[3]);
  }
  if (n4 < s.n) {
    const SoaSources rest{s.x + n4, s.y + n4, s.z + n4, s.q + n4, s.g + n4, s.n - n4};
    accumulate_scalar(t, rest, eps2);
  }
}

#endif

using Kernel = void (*)(const SoaTargets&, const SoaSources&, double);

Kernel choose() {
#ifdef ALLOY_DIRECT_KERNEL_X86
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f")) return accumulate_avx512;
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return accumulate_avx2;
#endif
  return accumulate_scalar;
}

Kernel kernel() {
  static const Kernel chosen = choose();
  return chosen;
}

}  // namespace

void direct_accumulate(const SoaTargets& targets, const SoaSources& sources, double eps2) {
  if (targets.n == 0 || sources.n == 0) return;
  kernel()(targets, sources, eps2);
}

bool direct_accumulate_mutual(const SoaTargets& targets, const double* tq,
                              const SoaSources& sources, double* sfx, double* sfy, double* sfz,
                              double eps2) {
#ifdef ALLOY_DIRECT_KERNEL_X86
  if (kernel() == accumulate_avx512) {
    if (targets.n != 0 && sources.n != 0) mutual_avx512(targets, tq, sources, sfx, sfy, sfz, eps2);
    return true;
  }
#endif
  (void)targets, (void)tq, (void)sources, (void)sfx, (void)sfy, (void)sfz, (void)eps2;
  return false;
}

bool direct_accumulate_single(const SoaTargetsF& targets, const SoaSourcesF& sources, float eps2) {
#ifdef ALLOY_DIRECT_KERNEL_X86
  if (kernel() == accumulate_avx512) {
    if (targets.n != 0 && sources.n != 0) accumulate_f32(targets, sources, eps2);
    return true;
  }
#endif
  (void)targets, (void)sources, (void)eps2;
  return false;
}

bool direct_accumulate_mutual_single(const SoaTargetsF& targets, const float* tq,
                                     const SoaSourcesF& sources, float* sfx, float* sfy, float* sfz,
                                     float eps2) {
#ifdef ALLOY_DIRECT_KERNEL_X86
  if (kernel() == accumulate_avx512) {
    if (targets.n != 0 && sources.n != 0) mutual_f32(targets, tq, sources, sfx, sfy, sfz, eps2);
    return true;
  }
#endif
  (void)targets, (void)tq, (void)sources, (void)sfx, (void)sfy, (void)sfz, (void)eps2;
  return false;
}

void direct_accumulate_mutual_scalar(const SoaTargets& targets, const double* tq,
                                     const SoaSources& sources, double* sfx, double* sfy,
                                     double* sfz, double eps2) {
  mutual_scalar(targets, tq, sources, sfx, sfy, sfz, eps2);
}

const char* direct_kernel_isa() {
#ifdef ALLOY_DIRECT_KERNEL_X86
  if (kernel() == accumulate_avx512) return "avx512";
  if (kernel() == accumulate_avx2) return "avx2";
#endif
  return "scalar";
}

bool direct_accumulate_with(const char* isa, const SoaTargets& targets, const SoaSources& sources,
                            double eps2) {
  const std::string_view want(isa);
  Kernel k = nullptr;
  if (want == "scalar") k = accumulate_scalar;
#ifdef ALLOY_DIRECT_KERNEL_X86
  __builtin_cpu_init();
  if (want == "avx512" && __builtin_cpu_supports("avx512f")) k = accumulate_avx512;
  if (want == "avx2" && __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
    k = accumulate_avx2;
#endif
  if (!k) return false;
  if (targets.n != 0 && sources.n != 0) k(targets, sources, eps2);
  return true;
}

}  // namespace alloy::multipole
