#include "resolvers/common/multipole_tree.hpp"

#include <algorithm>
#include <cmath>

#include "resolvers/common/direct_kernel.hpp"
#include "resolvers/common/fmm.hpp"

namespace alloy::multipole {

namespace {
// Below this a cube is not split further, whatever it holds: sources at one
// point (or nearly) would otherwise recurse without end.
constexpr int kMaxDepth = 40;
}  // namespace

// The cell's expansion (Tree::cell_field) at m targets, written as one loop
// over arrays so that the compiler vectorises it; cloned for AVX-512 and AVX2
// and chosen at load time where the toolchain can (ifunc), so that portable
// builds use the wide registers too.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx512f", "avx2", "default")))
#endif
void add_cell_field_arrays(const double* c, const double* oct, double q, const double* dip,
                           const double* quad, const double* __restrict tx,
                           const double* __restrict ty, const double* __restrict tz, std::size_t m,
                           double eps2, double* __restrict fx, double* __restrict fy,
                           double* __restrict fz) {
  // The cell's numbers in locals: the loop then reads only the targets.
  const double cx = c[0], cy = c[1], cz = c[2], d0 = dip[0], d1 = dip[1], d2 = dip[2];
  const double m0 = quad[0], m1 = quad[1], m2 = quad[2], m3 = quad[3], m4 = quad[4], m5 = quad[5];
  const double o0 = oct[0], o1 = oct[1], o2 = oct[2], o3 = oct[3], o4 = oct[4], o5 = oct[5],
               o6 = oct[6], o7 = oct[7], o8 = oct[8], o9 = oct[9];
  const double tr = m0 + m1 + m2;
  const double t0 = o0 + o5 + o7, t1 = o3 + o1 + o8, t2 = o4 + o6 + o2;
  for (std::size_t i = 0; i < m; ++i) {
    const double rx = tx[i] - cx, ry = ty[i] - cy, rz = tz[i] - cz;
    const double s2 = rx * rx + ry * ry + rz * rz + eps2;
    const double inv_s2 = 1.0 / s2;
    const double inv3 = inv_s2 / std::sqrt(s2);
    const double inv5 = inv3 * inv_s2, inv7 = inv5 * inv_s2, inv9 = inv7 * inv_s2;
    const double mrx = m0 * rx + m3 * ry + m4 * rz;
    const double mry = m3 * rx + m1 * ry + m5 * rz;
    const double mrz = m4 * rx + m5 * ry + m2 * rz;
    const double rmr = rx * mrx + ry * mry + rz * mrz;
    const double xx = rx * rx, yy = ry * ry, zz = rz * rz, xy = rx * ry, xz = rx * rz, yz = ry * rz;
    const double orx = o0 * xx + o5 * yy + o7 * zz + 2 * (o3 * xy + o4 * xz + o9 * yz);
    const double ory = o3 * xx + o1 * yy + o8 * zz + 2 * (o5 * xy + o9 * xz + o6 * yz);
    const double orz = o4 * xx + o6 * yy + o2 * zz + 2 * (o9 * xy + o7 * xz + o8 * yz);
    const double orrr = orx * rx + ory * ry + orz * rz;
    const double tdr = t0 * rx + t1 * ry + t2 * rz;
    const double dr = d0 * rx + d1 * ry + d2 * rz;
    const double radial = q * inv3 + 3.0 * dr * inv5 + 7.5 * rmr * inv7 - 1.5 * tr * inv5 +
                          17.5 * orrr * inv9 - 7.5 * tdr * inv7;
    fx[i] += rx * radial - d0 * inv3 - mrx * (3.0 * inv5) - orx * (7.5 * inv7) + t0 * (1.5 * inv5);
    fy[i] += ry * radial - d1 * inv3 - mry * (3.0 * inv5) - ory * (7.5 * inv7) + t1 * (1.5 * inv5);
    fz[i] += rz * radial - d2 * inv3 - mrz * (3.0 * inv5) - orz * (7.5 * inv7) + t2 * (1.5 * inv5);
  }
}

Vec3 direct_sum(std::span<const Source> sources, double softening, Vec3 x, std::uint32_t exclude) {
  const double eps2 = softening * softening;
  Vec3 f{};
  for (const Source& s : sources) {
    if (s.strength == 0 || (exclude != kNoGroup && s.group == exclude)) continue;
    f += kernel(x - s.position, eps2) * s.strength;
  }
  return f;
}

Tree::Tree() = default;
Tree::~Tree() = default;
Tree::Tree(Tree&&) noexcept = default;
Tree& Tree::operator=(Tree&&) noexcept = default;

void Tree::build(std::span<const Source> sources, double softening, TreeOptions options) {
  eps2_ = softening * softening;
  use_fmm_ = options.fmm_order > 0;
  if (use_fmm_) {
    if (!fmm_) fmm_ = std::make_unique<Fmm>();
    fmm_->build(sources, softening,
                {.theta = options.theta,
                 .order = options.fmm_order,
                 .leaf_size = options.leaf_size,
                 .single_near = options.fmm_single_near,
                 .reuse = options.reuse,
                 .pair_orders = options.fmm_pair_orders});
    // evaluate() sums directly over these; the cells are left as they were
    // but never used (the next Barnes-Hut build cannot refit them).
    sources_.assign(sources.begin(), sources.end());
    nodes_.clear();
    cell_interactions_ = direct_interactions_ = 0;
    refitted_ = false;
    return;
  }
  const double theta = std::clamp(options.theta, 1e-3, 0.99);
  theta2_ = theta * theta;
  block_ = std::max<std::uint32_t>(1, options.block);
  cell_interactions_ = direct_interactions_ = 0;
  refitted_ = options.reuse && std::max<std::uint32_t>(1, options.leaf_size) == leaf_size_ &&
              try_refit(sources);
  if (refitted_) return;
  leaf_size_ = std::max<std::uint32_t>(1, options.leaf_size);
  nodes_.clear();
  const auto n = std::uint32_t(sources.size());
  order_.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) order_[i] = i;
  sources_.assign(sources.begin(), sources.end());
  if (n == 0) {
    finish_build();
    return;
  }

  Vec3 lo = sources[0].position, hi = lo;
  for (const Source& s : sources) {
    lo = {std::min(lo.x, s.position.x), std::min(lo.y, s.position.y), std::min(lo.z, s.position.z)};
    hi = {std::max(hi.x, s.position.x), std::max(hi.y, s.position.y), std::max(hi.z, s.position.z)};
  }
  const Vec3 mid = (lo + hi) * 0.5;
  // A little margin so that no source sits exactly on the root's faces.
  const double half = 0.5 * std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}) * (1 + 1e-9) + 1e-12;

  scratch_.resize(n);
  nodes_.reserve(2 * (n / leaf_size_ + 1));
  make_node(mid, half, 0, n, 0);

  // Sources in tree order, so that a cell's sources are contiguous in memory.
  std::vector<Source> ordered(n);
  for (std::uint32_t t = 0; t < n; ++t) {
    ordered[t] = sources[order_[t]];
  }
  sources_ = std::move(ordered);
  for (Node& node : nodes_) moments(node);
  finish_build();
}

bool Tree::try_refit(std::span<const Source> sources) {
  const std::size_t n = sources.size();
  if (nodes_.empty() || n != sources_.size() || built_b2_.size() != nodes_.size()) return false;
  // The same sources: the same groups at the same tree positions, and the same
  // signs (a cell's centre and radius follow |q|, its neutrality the signs).
  for (std::size_t t = 0; t < n; ++t) {
    const Source& s = sources[order_[t]];
    const Source& was = sources_[t];
    if (s.group != was.group || (s.strength > 0) != (was.strength > 0) ||
        (s.strength < 0) != (was.strength < 0) || !is_finite(s.position))
      return false;
  }
  for (std::size_t t = 0; t < n; ++t) sources_[t] = sources[order_[t]];
  for (std::size_t k = 0; k < nodes_.size(); ++k) {
    moments(nodes_[k]);
    // A cell grown past 1.5 times its built radius is still correct (its
    // radius is current) but slow: rebuild.
    if (nodes_[k].b2 > 2.25 * built_b2_[k] && nodes_[k].end - nodes_[k].begin > 1) {
      nodes_.clear();  // build() starts afresh
      return false;
    }
  }
  for (std::size_t t = 0; t < n; ++t) {
    sx_[t] = sources_[t].position.x, sy_[t] = sources_[t].position.y,
    sz_[t] = sources_[t].position.z, sq_[t] = sources_[t].strength;
  }
  return true;
}

void Tree::finish_build() {
  const std::size_t n = sources_.size();
  built_b2_.resize(nodes_.size());
  for (std::size_t k = 0; k < nodes_.size(); ++k) built_b2_[k] = nodes_[k].b2;
  sx_.resize(n), sy_.resize(n), sz_.resize(n), sq_.resize(n), sg_.resize(n);
  for (std::size_t t = 0; t < n; ++t) {
    const Source& s = sources_[t];
    sx_[t] = s.position.x, sy_[t] = s.position.y, sz_[t] = s.position.z, sq_[t] = s.strength;
    sg_[t] = s.group == kNoGroup ? -1.0 : double(s.group);
  }

  // Group -> members (tree positions), for excluding a target's own group from
  // a cell used whole.
  std::uint32_t groups = 0;
  for (const Source& s : sources_)
    if (s.group != kNoGroup) groups = std::max(groups, s.group + 1);
  group_start_.assign(groups + 1, 0);
  for (const Source& s : sources_)
    if (s.group != kNoGroup) ++group_start_[s.group + 1];
  for (std::uint32_t g = 0; g < groups; ++g) group_start_[g + 1] += group_start_[g];
  group_members_.resize(group_start_[groups]);
  std::vector<std::uint32_t> fill(group_start_.begin(), group_start_.end() - 1);
  for (std::uint32_t t = 0; t < n; ++t)
    if (sources_[t].group != kNoGroup) group_members_[fill[sources_[t].group]++] = t;
}

std::int32_t Tree::make_node(Vec3 box_centre, double half, std::uint32_t begin, std::uint32_t end,
                             int depth) {
  const auto index = std::int32_t(nodes_.size());
  nodes_.emplace_back();
  {
    Node& node = nodes_.back();
    node.box_centre = box_centre;
    node.half = half;
    node.begin = begin;
    node.end = end;
    std::fill(std::begin(node.child), std::end(node.child), -1);
  }
  if (end - begin <= leaf_size_ || depth >= kMaxDepth) return index;

  // Counting sort of [begin, end) into the eight octants (stable: deterministic).
  auto octant = [&](std::uint32_t i) {
    const Vec3 p = sources_[i].position;
    return int(p.x >= box_centre.x) | int(p.y >= box_centre.y) << 1 | int(p.z >= box_centre.z) << 2;
  };
  std::uint32_t count[9] = {};
  for (std::uint32_t t = begin; t < end; ++t) ++count[octant(order_[t]) + 1];
  for (int o = 0; o < 8; ++o) count[o + 1] += count[o];
  std::uint32_t next[8];
  for (int o = 0; o < 8; ++o) next[o] = begin + count[o];
  for (std::uint32_t t = begin; t < end; ++t) scratch_[next[octant(order_[t])]++] = order_[t];
  std::copy(scratch_.begin() + begin, scratch_.begin() + end, order_.begin() + begin);

  nodes_[index].leaf = false;
  const double h = 0.5 * half;
  for (int o = 0; o < 8; ++o) {
    const std::uint32_t b = begin + count[o], e = begin + count[o + 1];
    if (b == e) continue;
    const Vec3 c{box_centre.x + ((o & 1) ? h : -h), box_centre.y + ((o & 2) ? h : -h),
                 box_centre.z + ((o & 4) ? h : -h)};
    const std::int32_t child = make_node(c, h, b, e, depth + 1);
    nodes_[index].child[o] = child;
  }
  return index;
}

void Tree::moments(Node& n) const {
  // Expansion centre: the |q|-weighted centroid. For neutral cells (whole
  // magnets) the charge centroid is undefined; this one stays inside the cell.
  double w = 0;
  Vec3 c{};
  for (std::uint32_t t = n.begin; t < n.end; ++t) {
    const double a = std::abs(sources_[t].strength);
    w += a;
    c += sources_[t].position * a;
  }
  n.empty = !(w > 0);
  if (n.empty) return;
  c = c / w;
  n.centre = c;
  double b2 = 0, q = 0;
  Vec3 d{};
  double m[6] = {}, o[10] = {};
  for (std::uint32_t t = n.begin; t < n.end; ++t) {
    const Source& s = sources_[t];
    const Vec3 r = s.position - c;
    b2 = std::max(b2, dot(r, r));
    q += s.strength;
    d += r * s.strength;
    m[0] += s.strength * r.x * r.x;
    m[1] += s.strength * r.y * r.y;
    m[2] += s.strength * r.z * r.z;
    m[3] += s.strength * r.x * r.y;
    m[4] += s.strength * r.x * r.z;
    m[5] += s.strength * r.y * r.z;
    const double qx = s.strength * r.x, qy = s.strength * r.y, qz = s.strength * r.z;
    o[0] += qx * r.x * r.x;
    o[1] += qy * r.y * r.y;
    o[2] += qz * r.z * r.z;
    o[3] += qx * r.x * r.y;
    o[4] += qx * r.x * r.z;
    o[5] += qx * r.y * r.y;
    o[6] += qy * r.y * r.z;
    o[7] += qx * r.z * r.z;
    o[8] += qy * r.z * r.z;
    o[9] += qx * r.y * r.z;
  }
  n.b2 = b2;
  n.reach = std::sqrt(b2 / theta2_);
  n.q = q;
  n.d = d;
  std::copy(std::begin(m), std::end(m), std::begin(n.m));
  std::copy(std::begin(o), std::end(o), std::begin(n.o));
}

Vec3 Tree::cell_field(const Node& n, Vec3 x) const {
  // The cell whole: the softened kernel's Taylor expansion about its centre c.
  // With r = x - c, s^2 = |r|^2 + eps^2, moments Q, D_a, M_ab, O_abc of the
  // offsets d_j = p_j - c, T_a = O_abb:
  //   sum q_j K(r - d_j) = Q r/s^3
  //     + 3 (D.r) r/s^5 - D/s^3
  //     + 7.5 (r.M.r) r/s^7 - 1.5 tr(M) r/s^5 - 3 M.r/s^5
  //     + 17.5 (O:rrr) r/s^9 - 7.5 (T.r) r/s^7 - 7.5 (O:rr)/s^7 + 1.5 T/s^5
  // (derivatives of 1/s; docs/magnetism.md, "Summation").
  const Vec3 r = x - n.centre;
  const double s2 = dot(r, r) + eps2_;
  const double inv_s2 = 1.0 / s2;
  const double inv3 = inv_s2 / std::sqrt(s2);
  const double inv5 = inv3 * inv_s2;
  const double inv7 = inv5 * inv_s2;
  const double inv9 = inv7 * inv_s2;
  const double* m = n.m;
  const Vec3 mr{m[0] * r.x + m[3] * r.y + m[4] * r.z, m[3] * r.x + m[1] * r.y + m[5] * r.z,
                m[4] * r.x + m[5] * r.y + m[2] * r.z};
  const double rmr = dot(r, mr);
  const double tr = m[0] + m[1] + m[2];
  const double* o = n.o;
  // O:rr, component a = O_abc r_b r_c.
  const double xx = r.x * r.x, yy = r.y * r.y, zz = r.z * r.z;
  const double xy = r.x * r.y, xz = r.x * r.z, yz = r.y * r.z;
  const Vec3 orr{o[0] * xx + o[5] * yy + o[7] * zz + 2 * (o[3] * xy + o[4] * xz + o[9] * yz),
                 o[3] * xx + o[1] * yy + o[8] * zz + 2 * (o[5] * xy + o[9] * xz + o[6] * yz),
                 o[4] * xx + o[6] * yy + o[2] * zz + 2 * (o[9] * xy + o[7] * xz + o[8] * yz)};
  const double orrr = dot(orr, r);
  const Vec3 t{o[0] + o[5] + o[7], o[3] + o[1] + o[8], o[4] + o[6] + o[2]};
  const double tdr = dot(t, r);
  const double radial = n.q * inv3 + 3.0 * dot(n.d, r) * inv5 + 7.5 * rmr * inv7 - 1.5 * tr * inv5 +
                        17.5 * orrr * inv9 - 7.5 * tdr * inv7;
  return r * radial - n.d * inv3 - mr * (3.0 * inv5) - orr * (7.5 * inv7) + t * (1.5 * inv5);
}

void Tree::add_cell_field(const Node& n, const double* x, const double* y, const double* z,
                          std::size_t m, double eps2, double* fx, double* fy, double* fz) {
  const double c[3] = {n.centre.x, n.centre.y, n.centre.z}, d[3] = {n.d.x, n.d.y, n.d.z};
  add_cell_field_arrays(c, n.o, n.q, d, n.m, x, y, z, m, eps2, fx, fy, fz);
}

void Tree::walk(std::span<const Vec3> x, std::uint32_t exclude, std::uint32_t self,
                std::span<Vec3> out) const {
  for (Vec3& f : out) f = {};
  if (nodes_.empty() || x.empty()) return;
  const bool grouped = exclude != kNoGroup && exclude + 1 < group_start_.size();
  // The targets' bounding sphere: a cell is used whole only if it is far from
  // all of them, and then for all of them, so that the errors at a magnet's
  // two poles are alike and cancel in its net force as the forces do.
  Vec3 centre{};
  for (const Vec3& p : x) centre += p;
  centre = centre / double(x.size());
  double radius = 0;
  for (const Vec3& p : x) radius = std::max(radius, length(p - centre));

  stack_.clear();
  stack_.push_back(0);
  std::uint64_t cells = 0, pairs = 0;
  while (!stack_.empty()) {
    const Node& n = nodes_[stack_.back()];
    stack_.pop_back();
    if (n.empty) continue;
    // b_max < theta (|x_g - c| - r_g), squared to spare a square root per cell.
    const Vec3 gap = centre - n.centre;
    const double reach = n.reach + radius;
    if (dot(gap, gap) > reach * reach) {
      cells += x.size();
      for (std::size_t i = 0; i < x.size(); ++i) out[i] += cell_field(n, x[i]);
      if (grouped) {
        // The targets' own group must not act on them: take out, exactly,
        // those of its members the cell included (few: a magnet has two poles).
        for (std::uint32_t k = group_start_[exclude]; k < group_start_[exclude + 1]; ++k) {
          const std::uint32_t t = group_members_[k];
          if (t < n.begin || t >= n.end) continue;
          for (std::size_t i = 0; i < x.size(); ++i)
            out[i] -= kernel(x[i] - sources_[t].position, eps2_) * sources_[t].strength;
        }
      }
    } else if (n.leaf) {
      for (std::uint32_t t = n.begin; t < n.end; ++t) {
        const Source& s = sources_[t];
        if (t == self || s.strength == 0 || (exclude != kNoGroup && s.group == exclude)) continue;
        for (std::size_t i = 0; i < x.size(); ++i)
          out[i] += kernel(x[i] - s.position, eps2_) * s.strength;
      }
      pairs += (n.end - n.begin) * x.size();
    } else {
      for (int o = 7; o >= 0; --o)
        if (n.child[o] >= 0) stack_.push_back(n.child[o]);
    }
  }
  cell_interactions_ += cells;
  direct_interactions_ += pairs;
}

Vec3 Tree::evaluate(Vec3 x, std::uint32_t exclude) const {
  if (use_fmm_) return direct_sum(sources_, std::sqrt(eps2_), x, exclude);
  Vec3 f;
  walk(std::span(&x, 1), exclude, 0xffffffffu, std::span(&f, 1));
  return f;
}

void Tree::evaluate_at_sources(std::span<Vec3> out) const {
  if (use_fmm_) {
    fmm_->evaluate_at_sources(out);
    cell_interactions_ = fmm_->cell_interactions();
    direct_interactions_ = fmm_->direct_interactions();
    return;
  }
  const auto n = std::uint32_t(sources_.size());
  if (n == 0) return;
  // The block's targets (tree positions) and their arrays.
  std::vector<std::uint32_t> members;
  std::vector<double> tx, ty, tz, tg, fx, fy, fz;
  std::vector<std::int32_t> far;                              // cells used whole
  std::vector<std::pair<std::uint32_t, std::uint32_t>> near;  // source ranges summed directly
  std::vector<double> near_x, near_y, near_z, near_q, near_g;
  std::uint64_t cells = 0, pairs = 0;
  auto flush = [&] {
    if (members.empty()) return;
    const std::size_t m = members.size();
    tx.resize(m), ty.resize(m), tz.resize(m), tg.resize(m);
    fx.assign(m, 0.0), fy.assign(m, 0.0), fz.assign(m, 0.0);
    Vec3 centre{};
    for (std::size_t i = 0; i < m; ++i) {
      const Source& s = sources_[members[i]];
      tx[i] = s.position.x, ty[i] = s.position.y, tz[i] = s.position.z;
      // Ungrouped targets: -2, which no source carries (self is r = 0).
      tg[i] = s.group == kNoGroup ? -2.0 : double(s.group);
      centre += s.position;
    }
    centre = centre / double(m);
    double radius2 = 0;
    for (std::size_t i = 0; i < m; ++i) {
      const Vec3 d = sources_[members[i]].position - centre;
      radius2 = std::max(radius2, dot(d, d));
    }
    // Widened a little past rounding: a cell of one source has radius 0, and
    // when that source is a target's own partner (at exactly the sphere's
    // radius) the test below must not take it whole by a rounding error.
    const double radius =
        std::sqrt(radius2) * (1 + 1e-9) +
        1e-12 * std::max({std::abs(centre.x), std::abs(centre.y), std::abs(centre.z)});

    // One walk for the block. A cell is used whole only if it is farther than
    // its reach from every point of the block's sphere, which holds all the
    // poles of the block's groups: a target's own group is then never inside
    // a cell used whole, and the near field's kernel leaves it out by group.
    far.clear(), near.clear();
    stack_.clear();
    stack_.push_back(0);
    while (!stack_.empty()) {
      const Node& node = nodes_[stack_.back()];
      const std::int32_t index = stack_.back();
      stack_.pop_back();
      if (node.empty) continue;
      const Vec3 gap = centre - node.centre;
      const double reach = node.reach + radius;
      if (dot(gap, gap) > reach * reach) {
        far.push_back(index);
      } else if (node.leaf) {
        if (!near.empty() && near.back().second == node.begin)
          near.back().second = node.end;  // neighbours in memory: one run
        else
          near.emplace_back(node.begin, node.end);
      } else {
        for (int o = 7; o >= 0; --o)
          if (node.child[o] >= 0) stack_.push_back(node.child[o]);
      }
    }
    for (std::int32_t k : far)
      add_cell_field(nodes_[k], tx.data(), ty.data(), tz.data(), m, eps2_, fx.data(), fy.data(),
                     fz.data());
    const SoaTargets targets{tx.data(), ty.data(), tz.data(), tg.data(),
                             fx.data(), fy.data(), fz.data(), m};
    // The near sources gathered into one run, so that the kernel sums each
    // target's lanes once rather than once per leaf.
    near_x.clear(), near_y.clear(), near_z.clear(), near_q.clear(), near_g.clear();
    for (const auto& [b, e] : near) {
      near_x.insert(near_x.end(), sx_.begin() + b, sx_.begin() + e);
      near_y.insert(near_y.end(), sy_.begin() + b, sy_.begin() + e);
      near_z.insert(near_z.end(), sz_.begin() + b, sz_.begin() + e);
      near_q.insert(near_q.end(), sq_.begin() + b, sq_.begin() + e);
      near_g.insert(near_g.end(), sg_.begin() + b, sg_.begin() + e);
    }
    direct_accumulate(
        targets,
        {near_x.data(), near_y.data(), near_z.data(), near_q.data(), near_g.data(), near_x.size()},
        eps2_);
    pairs += std::uint64_t(near_x.size()) * m;
    cells += far.size() * m;
    for (std::size_t i = 0; i < m; ++i) out[order_[members[i]]] = {fx[i], fy[i], fz[i]};
    members.clear();
  };

  for (std::uint32_t t = 0; t < n; ++t) {
    const std::uint32_t g = sources_[t].group;
    const bool grouped = g != kNoGroup && g + 1 < group_start_.size();
    // A group joins a block whole, when its first member (in tree order) comes.
    if (grouped && group_members_[group_start_[g]] != t) continue;
    const std::uint32_t size = grouped ? group_start_[g + 1] - group_start_[g] : 1;
    if (!members.empty() && members.size() + size > block_) flush();
    if (grouped)
      members.insert(members.end(), group_members_.begin() + group_start_[g],
                     group_members_.begin() + group_start_[g + 1]);
    else
      members.push_back(t);
  }
  flush();
  cell_interactions_ += cells;
  direct_interactions_ += pairs;
}

// The method before issue 16, kept for the bench's comparison: one walk per
// group (a magnet's two poles), scalar cells and pairs.
void Tree::evaluate_at_sources_per_group(std::span<Vec3> out) const {
  std::vector<Vec3> xs, fs;
  for (std::uint32_t t = 0; t < sources_.size(); ++t) {
    const std::uint32_t g = sources_[t].group;
    if (g == kNoGroup) {
      Vec3 f;
      walk(std::span(&sources_[t].position, 1), g, t, std::span(&f, 1));
      out[order_[t]] = f;
      continue;
    }
    // A group is evaluated once, when its first member (in tree order) comes.
    const std::uint32_t* first = group_members_.data() + group_start_[g];
    const std::uint32_t* last = group_members_.data() + group_start_[g + 1];
    if (*first != t) continue;
    xs.clear();
    for (const std::uint32_t* m = first; m != last; ++m) xs.push_back(sources_[*m].position);
    fs.resize(xs.size());
    walk(xs, g, t, fs);
    for (std::size_t i = 0; i < xs.size(); ++i) out[order_[first[i]]] = fs[i];
  }
}

void direct_at_sources(std::span<const Source> sources, double softening, std::span<Vec3> out) {
  const std::size_t n = sources.size();
  std::vector<double> x(n), y(n), z(n), q(n), g(n), tg(n), fx(n, 0.0), fy(n, 0.0), fz(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const Source& s = sources[i];
    x[i] = s.position.x, y[i] = s.position.y, z[i] = s.position.z, q[i] = s.strength;
    g[i] = s.group == kNoGroup ? -1.0 : double(s.group);
    tg[i] = s.group == kNoGroup ? -2.0 : g[i];
  }
  direct_accumulate({x.data(), y.data(), z.data(), tg.data(), fx.data(), fy.data(), fz.data(), n},
                    {x.data(), y.data(), z.data(), q.data(), g.data(), n}, softening * softening);
  for (std::size_t i = 0; i < n; ++i) out[i] = {fx[i], fy[i], fz[i]};
}

}  // namespace alloy::multipole
