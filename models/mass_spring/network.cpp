#include "models/mass_spring/network.hpp"

#include "models/detail/with_dim.hpp"

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <tuple>
#include <type_traits>
#include <unordered_map>
#include <unordered_set>
#include <utility>

namespace stiffbench {

namespace {

// Runs body(p) for p in [0, n), over OpenMP threads when `parallel`. Each p is independent, so
// the result does not depend on the thread count.
template <class Body>
void for_points(Index n, bool parallel, const Body& body) {
  if (parallel) {
#pragma omp parallel for schedule(static)
    for (Index p = 0; p < n; ++p) body(p);
  } else {
    for (Index p = 0; p < n; ++p) body(p);
  }
}

std::string item(const char* what, std::size_t index) {
  return std::string(what) + " " + std::to_string(index);
}

}  // namespace

MassSpringNetwork::MassSpringNetwork(std::string name, int dim, std::vector<MassPoint> points,
                                     std::vector<Spring> springs, NetworkOptions options,
                                     std::vector<DistanceConstraint> constraints,
                                     std::vector<Triangle> triangles)
    : name_(std::move(name)),
      dim_(dim),
      points_(std::move(points)),
      springs_(std::move(springs)),
      triangles_(std::move(triangles)),
      opt_(options) {
  const std::string who = name_ + ": ";
  // Per-item checks build their message only when they fail (a 512² cloth has 1.5 M springs).
  const auto check = [](bool ok, const auto& message) {
    if (!ok) throw BadInput(message());
  };
  require_input(dim_ >= 1 && dim_ <= 3, who + "dimension must be 1, 2 or 3");
  require_input(!points_.empty(), who + "the network has no points");
  const Index np = num_points();
  for (int c = dim_; c < 3; ++c)
    require_input(opt_.gravity[static_cast<std::size_t>(c)] == 0.0,
                  who + "gravity has a component beyond the network's dimension");
  for (int c = 0; c < dim_; ++c)
    require_input(std::isfinite(opt_.gravity[static_cast<std::size_t>(c)]),
                  who + "gravity must be finite");
  require_input(std::isfinite(opt_.point_damping) && opt_.point_damping >= 0,
                who + "point damping must be >= 0");
  for (std::size_t p = 0; p < points_.size(); ++p) {
    MassPoint& pt = points_[p];
    check(std::isfinite(pt.mass) && pt.mass > 0,
          [&] { return who + item("point", p) + ": mass <= 0"; });
    for (int c = 0; c < 3; ++c) {
      const auto cc = static_cast<std::size_t>(c);
      check(std::isfinite(pt.x[cc]) && std::isfinite(pt.v[cc]),
            [&] { return who + item("point", p) + ": non-finite state"; });
      if (c >= dim_)
        check(pt.x[cc] == 0.0 && pt.v[cc] == 0.0,
              [&] { return who + item("point", p) + ": component beyond the dimension"; });
    }
    if (pt.pinned) pt.v = {0.0, 0.0, 0.0};
  }
  for (std::size_t e = 0; e < springs_.size(); ++e) {
    const Spring& s = springs_[e];
    check(s.i >= 0 && s.i < np && s.j >= 0 && s.j < np && s.i != s.j,
          [&] { return who + item("spring", e) + ": bad end points"; });
    check(std::isfinite(s.k) && s.k >= 0,
          [&] { return who + item("spring", e) + ": stiffness < 0"; });
    check(std::isfinite(s.rest) && s.rest >= 0,
          [&] { return who + item("spring", e) + ": rest length < 0"; });
    check(std::isfinite(s.damping) && s.damping >= 0,
          [&] { return who + item("spring", e) + ": dashpot coefficient < 0"; });
  }
  for (std::size_t c = 0; c < constraints.size(); ++c) {
    const DistanceConstraint& dc = constraints[c];
    check(dc.i >= 0 && dc.i < np && dc.j >= 0 && dc.j < np && dc.i != dc.j,
          [&] { return who + item("constraint", c) + ": bad end points"; });
    check(std::isfinite(dc.length) && dc.length > 0,
          [&] { return who + item("constraint", c) + ": length <= 0"; });
  }

  distance_constraints_ = DistanceConstraints(dim_, points_, std::move(constraints));
  check_triangles();
  if (drag()) {
    const auto count = static_cast<std::size_t>(np);
    point_face_start_.assign(count + 1, 0);
    for (const Triangle& t : triangles_)
      for (const Index p : {t.a, t.b, t.c}) ++point_face_start_[static_cast<std::size_t>(p) + 1];
    for (std::size_t p = 0; p < count; ++p) point_face_start_[p + 1] += point_face_start_[p];
    point_faces_.resize(3 * triangles_.size());
    std::vector<Index> fill(point_face_start_.begin(), point_face_start_.end() - 1);
    for (std::size_t t = 0; t < triangles_.size(); ++t)
      for (const Index p : {triangles_[t].a, triangles_[t].b, triangles_[t].c})
        point_faces_[static_cast<std::size_t>(fill[static_cast<std::size_t>(p)]++)] =
            static_cast<Index>(t);
    face_force_.resize(3 * triangles_.size());
  }

  velocity_dependent_ = opt_.point_damping != 0.0 || drag();
  for (const Spring& s : springs_) has_dashpots_ = has_dashpots_ || s.damping != 0.0;
  velocity_dependent_ = velocity_dependent_ || has_dashpots_;

  const Index n = dofs();
  y0_.resize(2 * n);
  dof_mass_.resize(n);
  inv_mass_.resize(points_.size());  // the Jacobian blocks' weights
  for (Index p = 0; p < np; ++p) {
    const MassPoint& pt = points_[static_cast<std::size_t>(p)];
    inv_mass_[static_cast<std::size_t>(p)] = pt.pinned ? 0.0 : 1.0 / pt.mass;
    for (int c = 0; c < dim_; ++c) {
      y0_[dim_ * p + c] = pt.x[static_cast<std::size_t>(c)];
      y0_[n + dim_ * p + c] = pt.v[static_cast<std::size_t>(c)];
      dof_mass_[dim_ * p + c] = pt.mass;
    }
  }

  point_mass_.resize(points_.size());
  pinned_.resize(points_.size());
  for (std::size_t p = 0; p < points_.size(); ++p) {
    point_mass_[p] = points_[p].mass;
    pinned_[p] = points_[p].pinned ? 1 : 0;
  }
  pack_rhs_springs();
  for (const Spring& sp : springs_)
    implicit_dashpots_ = implicit_dashpots_ || (implicit_spring(sp) && sp.damping != 0.0);

  // The adjacency lists and the Jacobian pattern are built on first use (build_structure): an
  // explicit run never needs them, and for a 512² cloth they are most of the construction cost.
}

// Air drag's triangles: valid points, and with drag every edge a spring (its blocks must be in
// the pattern of K and D).
void MassSpringNetwork::check_triangles() const {
  const std::string who = name_ + ": ";
  require_input(std::isfinite(opt_.air_drag) && opt_.air_drag >= 0,
                who + "air drag coefficient must be >= 0");
  if (triangles_.empty()) return;
  require_input(dim_ == 3, who + "triangles (air drag) need a 3D network");
  const Index np = num_points();
  std::unordered_set<std::uint64_t> edges;
  const auto key = [](Index i, Index j) {
    return (static_cast<std::uint64_t>(std::min(i, j)) << 32) |
           static_cast<std::uint64_t>(std::max(i, j));
  };
  if (opt_.air_drag > 0.0)
    for (const Spring& sp : springs_) edges.insert(key(sp.i, sp.j));
  for (std::size_t t = 0; t < triangles_.size(); ++t) {
    const Triangle& tr = triangles_[t];
    const Index v[3] = {tr.a, tr.b, tr.c};
    bool ok = tr.a != tr.b && tr.b != tr.c && tr.a != tr.c;
    for (Index p : v) ok = ok && p >= 0 && p < np;
    if (!ok) throw BadInput(who + item("triangle", t) + ": bad points");
    if (opt_.air_drag > 0.0)
      for (int e = 0; e < 3; ++e)
        if (!edges.count(key(v[e], v[(e + 1) % 3])))
          throw BadInput(who + item("triangle", t) +
                         ": an edge is not a spring (air drag's Jacobian blocks need it)");
  }
}

// Springs of the right-hand side in structure-of-arrays order, grouped by partition of the
// points (see the header comment and RhsSprings); within each group, the runs first, then the
// loose springs in the network's order.
void MassSpringNetwork::pack_rhs_springs() {
  const Index np = num_points();
  // The partition count depends on the size only (not on the threads or on the parallel
  // threshold), so the serial and the parallel path sum in the same order.
  const Index parts = np >= 64 * kRhsPartitions ? kRhsPartitions : 1;
  // part_of(p) inverts p0 = np·q/parts: the first q with np·(q+1)/parts > p.
  const auto owner = [&](Index p) {
    Index q = (p * parts) / np;
    while (q + 1 < parts && np * (q + 1) / parts <= p) ++q;
    while (q > 0 && np * q / parts > p) --q;
    return q;
  };
  std::vector<std::int32_t> part(static_cast<std::size_t>(np));
  for (Index p = 0; p < np; ++p)
    part[static_cast<std::size_t>(p)] = static_cast<std::int32_t>(owner(p));
  // Group of a spring: its partition q (both ends in q); parts + lo/2 for a spring between lo
  // and lo + 1 with lo even, parts + ne + lo/2 with lo odd; parts + ne + no for all others.
  rhs_parts_ = parts;
  even_groups_ = parts / 2;
  odd_groups_ = (parts - 1) / 2;
  const Index groups = parts + even_groups_ + odd_groups_ + 1;
  const auto group_of = [&](const Spring& sp) {
    const Index qi = part[static_cast<std::size_t>(sp.i)],
                qj = part[static_cast<std::size_t>(sp.j)];
    if (qi == qj) return qi;
    const Index lo = std::min(qi, qj), hi = std::max(qi, qj);
    if (hi != lo + 1) return groups - 1;
    return parts + (lo % 2 == 0 ? lo / 2 : even_groups_ + lo / 2);
  };

  // The distinct (k, L) pairs (by bits): a short linear search while there are few, then a hash.
  RhsSprings& rs = rhs_springs_;
  const std::size_t ns = springs_.size();
  require_input(dofs() <= std::numeric_limits<std::int32_t>::max(),
                name_ + ": more than 2^31 - 1 coordinates (the springs store 32-bit offsets)");
  struct KeyHash {
    std::size_t operator()(const std::pair<std::uint64_t, std::uint64_t>& key) const {
      return std::hash<std::uint64_t>()(key.first * 0x9E3779B97F4A7C15ULL ^ key.second);
    }
  };
  std::unordered_map<std::pair<std::uint64_t, std::uint64_t>, std::int32_t, KeyHash> kinds;
  const auto kind_of = [&](double k, double rest) {
    const std::pair<std::uint64_t, std::uint64_t> key{std::bit_cast<std::uint64_t>(k),
                                                      std::bit_cast<std::uint64_t>(rest)};
    if (kinds.empty()) {
      for (std::size_t t = 0; t < rs.k.size(); ++t)
        if (std::bit_cast<std::uint64_t>(rs.k[t]) == key.first &&
            std::bit_cast<std::uint64_t>(rs.rest[t]) == key.second)
          return static_cast<std::int32_t>(t);
      if (rs.k.size() == 16)  // from now on, a hash table
        for (std::size_t t = 0; t < rs.k.size(); ++t)
          kinds.emplace(std::pair{std::bit_cast<std::uint64_t>(rs.k[t]),
                                  std::bit_cast<std::uint64_t>(rs.rest[t])},
                        static_cast<std::int32_t>(t));
    } else if (const auto it = kinds.find(key); it != kinds.end()) {
      return it->second;
    }
    const auto t = static_cast<std::int32_t>(rs.k.size());
    rs.k.push_back(k);
    rs.rest.push_back(rest);
    if (!kinds.empty()) kinds.emplace(key, t);
    return t;
  };
  // Each spring's (k, L) pair and part, and the springs of each group in the network's order.
  std::vector<std::int32_t> kind(ns);
  std::vector<std::uint8_t> implicit(ns, 0);
  std::vector<std::vector<std::int32_t>> members(static_cast<std::size_t>(groups));
  for (std::size_t e = 0; e < ns; ++e) {
    const Spring& sp = springs_[e];
    kind[e] = kind_of(sp.k, sp.rest);
    implicit[e] = opt_.split != NetworkSplit::none && implicit_spring(sp) ? 1 : 0;
    members[static_cast<std::size_t>(group_of(sp))].push_back(static_cast<std::int32_t>(e));
  }

  rs.i.resize(ns);
  rs.j.resize(ns);
  rs.kind.resize(ns);
  rs.damping.assign(has_dashpots_ ? ns : 0, 0.0);
  if (opt_.split != NetworkSplit::none) packed_implicit_.assign(ns, 0);
  group_start_.assign(1, 0);
  group_loose_.clear();
  group_runs_.assign(1, 0);
  runs_.clear();
  std::vector<std::uint8_t> taken(ns, 0);
  std::size_t slot = 0;
  const auto place = [&](std::int32_t e) {
    const Spring& sp = springs_[static_cast<std::size_t>(e)];
    rs.i[slot] = static_cast<std::int32_t>(dim_ * sp.i);
    rs.j[slot] = static_cast<std::int32_t>(dim_ * sp.j);
    rs.kind[slot] = kind[static_cast<std::size_t>(e)];
    if (has_dashpots_) rs.damping[slot] = sp.damping;
    if (opt_.split != NetworkSplit::none)
      packed_implicit_[slot] = implicit[static_cast<std::size_t>(e)];
    ++slot;
  };
  for (const std::vector<std::int32_t>& m : members) {
    // Runs: springs of one (j - i, (k, L) pair, part) whose first ends are consecutive points.
    // Listing the springs by that key and then by i puts them together (a stable sort by
    // (key, i)): one bucket per key, in key order, each in the network's order and sorted by i
    // only when it is not already (a lattice lists its springs by first end). Runs shorter than
    // kMinRun stay loose.
    const auto key = [&](std::int32_t e) {
      const Spring& sp = springs_[static_cast<std::size_t>(e)];
      return std::tuple{sp.j - sp.i, kind[static_cast<std::size_t>(e)],
                        implicit[static_cast<std::size_t>(e)], sp.i};
    };
    std::map<std::tuple<Index, std::int32_t, std::uint8_t>, std::vector<std::int32_t>> buckets;
    for (const std::int32_t e : m) {
      const auto [off, kd, imp, i0] = key(e);
      buckets[{off, kd, imp}].push_back(e);
    }
    std::vector<std::int32_t> sorted;
    sorted.reserve(m.size());
    for (auto& [bucket_key, members_of_key] : buckets) {
      const auto first_end = [&](std::int32_t a, std::int32_t b) {
        return springs_[static_cast<std::size_t>(a)].i < springs_[static_cast<std::size_t>(b)].i;
      };
      if (!std::is_sorted(members_of_key.begin(), members_of_key.end(), first_end))
        std::stable_sort(members_of_key.begin(), members_of_key.end(), first_end);
      sorted.insert(sorted.end(), members_of_key.begin(), members_of_key.end());
    }
    for (std::size_t a = 0; a < sorted.size();) {
      std::size_t b = a + 1;
      const auto [off, kd, imp, i0] = key(sorted[a]);
      while (b < sorted.size()) {
        const auto [off_b, kd_b, imp_b, i_b] = key(sorted[b]);
        if (off_b != off || kd_b != kd || imp_b != imp || i_b != i0 + static_cast<Index>(b - a))
          break;
        ++b;
      }
      if (b - a >= static_cast<std::size_t>(kMinRun)) {
        const Spring& first = springs_[static_cast<std::size_t>(sorted[a])];
        runs_.push_back({static_cast<Index>(slot), static_cast<Index>(b - a),
                         static_cast<std::int32_t>(dim_ * first.i),
                         static_cast<std::int32_t>(dim_ * first.j), kd, imp});
        for (std::size_t t = a; t < b; ++t) {
          place(sorted[t]);
          taken[static_cast<std::size_t>(sorted[t])] = 1;
        }
      }
      a = b;
    }
    group_runs_.push_back(static_cast<Index>(runs_.size()));
    group_loose_.push_back(static_cast<Index>(slot));
    for (const std::int32_t e : m)
      if (!taken[static_cast<std::size_t>(e)]) place(e);
    group_start_.push_back(static_cast<Index>(slot));
  }

  // Each partition's longest run of points that no spring between partitions touches; and
  // whether the partitions form a chain (acceleration_chain): no spring in the last group (it
  // joins partitions that are not neighbours), and no point with springs of two groups.
  // touched_by[p]: the group of a spring between partitions at point p, -1 for none.
  std::vector<Index> touched_by(static_cast<std::size_t>(np), -1);
  chain_ok_ = parts >= 2 && members.back().empty();
  for (const Spring& sp : springs_)
    if (const Index grp = group_of(sp); grp >= parts) {
      for (const Index p : {sp.i, sp.j}) {
        const auto u = static_cast<std::size_t>(p);
        if (touched_by[u] >= 0 && touched_by[u] != grp) chain_ok_ = false;
        touched_by[u] = grp;
      }
    }
  late_clear_.assign(2 * static_cast<std::size_t>(parts), 0);
  for (Index q = 0; q < parts; ++q) {
    const Index p0 = np * q / parts, p1 = np * (q + 1) / parts;
    Index best_a = p0, best_b = p0;
    for (Index a = p0; a < p1;) {
      if (touched_by[static_cast<std::size_t>(a)] >= 0) {
        ++a;
        continue;
      }
      Index b = a;
      while (b < p1 && touched_by[static_cast<std::size_t>(b)] < 0) ++b;
      if (b - a > best_b - best_a) best_a = a, best_b = b;
      a = b;
    }
    late_clear_[2 * static_cast<std::size_t>(q)] = best_a;
    late_clear_[2 * static_cast<std::size_t>(q) + 1] = best_b;
  }
}

const SpringNetworkView* MassSpringNetwork::spring_network() const {
  std::call_once(view_once_, [this] {
    view_.dim = dim_;
    view_.mass.resize(points_.size());
    view_.pinned.resize(points_.size());
    for (std::size_t p = 0; p < points_.size(); ++p) {
      view_.mass[p] = points_[p].mass;
      view_.pinned[p] = points_[p].pinned;
    }
    view_.springs.reserve(springs_.size());
    for (const Spring& s : springs_) view_.springs.push_back({s.i, s.j, s.rest, s.k, s.damping});
    view_.gravity = opt_.gravity;
    view_.point_damping = opt_.point_damping;
    if (drag()) view_.other_forces = "air drag (parameter drag > 0)";
  });
  return &view_;
}

// The springs' adjacency lists (stiffness estimates, and the Jacobians' structure below), built
// once, on first use, by whichever thread gets there first.
void MassSpringNetwork::ensure_adjacency() const {
  std::call_once(adjacency_once_, [this] {
    adjacency_ = SpringAdjacency::build(num_points(), springs_);
    if (opt_.split == NetworkSplit::stretch) {
      implicit_adjacency_ = SpringAdjacency::build(num_points(), springs_of_part(true));
      explicit_adjacency_ = SpringAdjacency::build(num_points(), springs_of_part(false));
    }
  });
}

std::vector<Spring> MassSpringNetwork::springs_of_part(bool implicit) const {
  std::vector<Spring> part;
  for (const Spring& sp : springs_)
    if (implicit_spring(sp) == implicit) part.push_back(sp);
  return part;
}

// The fixed pattern of K and D with the value positions of every block (Jacobians), built once,
// on first use.
void MassSpringNetwork::ensure_structure() const {
  ensure_adjacency();
  std::call_once(structure_once_, [this] {
    structure_ = build_structure(springs_, adjacency_, drag());
    if (opt_.split == NetworkSplit::stretch)
      implicit_structure_ = build_structure(springs_of_part(true), implicit_adjacency_, false);
  });
}

MassSpringNetwork::Structure MassSpringNetwork::build_structure(const std::vector<Spring>& springs,
                                                                const SpringAdjacency& adjacency,
                                                                bool with_faces) const {
  const Index np = num_points();
  const Index n = dofs();
  Structure st;
  for (const Spring& sp : springs) st.dashpots = st.dashpots || sp.damping != 0.0;
  st.adjacency = &adjacency;
  const std::vector<Index>& start = adjacency.start;
  const std::vector<SpringNeighbour>& neighbours = adjacency.neighbours;
  SparseMat& pattern = st.pattern;

  // The fixed pattern of K and D: every point's diagonal block and one block per ordered pair
  // of spring ends (pinned rows included, as explicit zeros).
  // Built column by column (the pattern is structurally symmetric: column block q holds the
  // row blocks of q and of its neighbours), no triplet list.
  const Index d = dim_;
  {
    std::vector<int> outer(static_cast<std::size_t>(n) + 1, 0), inner;
    inner.reserve(static_cast<std::size_t>(d * d * (np + static_cast<Index>(neighbours.size()))));
    std::vector<Index> rows;
    for (Index q = 0; q < np; ++q) {
      rows.clear();
      rows.push_back(q);
      for (Index e = start[static_cast<std::size_t>(q)]; e < start[static_cast<std::size_t>(q) + 1];
           ++e)
        rows.push_back(neighbours[static_cast<std::size_t>(e)].other);
      std::sort(rows.begin(), rows.end());
      rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
      for (Index b = 0; b < d; ++b) {
        for (Index p : rows)
          for (Index a = 0; a < d; ++a) inner.push_back(static_cast<int>(d * p + a));
        outer[static_cast<std::size_t>(d * q + b) + 1] = static_cast<int>(inner.size());
      }
    }
    const std::vector<double> zeros(inner.size(), 0.0);
    pattern = Eigen::Map<const SparseMat>(n, n, static_cast<Index>(inner.size()), outer.data(),
                                          inner.data(), zeros.data());
    pattern.makeCompressed();
  }
  st.diag_pattern.resize(n, n);
  st.diag_pattern.setIdentity();
  st.diag_pattern.makeCompressed();
  std::fill(st.diag_pattern.valuePtr(), st.diag_pattern.valuePtr() + n, 0.0);
  auto position = [&](Index row, Index col) {
    using StorageIndex = SparseMat::StorageIndex;
    const StorageIndex* inner = pattern.innerIndexPtr();
    const StorageIndex* begin = inner + pattern.outerIndexPtr()[col];
    const StorageIndex* end = inner + pattern.outerIndexPtr()[col + 1];
    const StorageIndex* it = std::lower_bound(begin, end, static_cast<StorageIndex>(row));
    if (it == end || *it != row) throw std::logic_error("mass-spring pattern lookup failed");
    return static_cast<Index>(it - inner);
  };
  // Every column of block q has the same row list, each row block contiguous: entry (a, b) of
  // block (p, q) sits at position(d p, d q) + a + b · (column length). One search per block.
  const auto block = [&](Index p, Index q, std::vector<Index>& out, std::size_t at) {
    const Index base = position(d * p, d * q);
    const Index len = pattern.outerIndexPtr()[d * q + 1] - pattern.outerIndexPtr()[d * q];
    for (Index a = 0; a < d; ++a)
      for (Index b = 0; b < d; ++b)
        out[at + static_cast<std::size_t>(a * d + b)] = base + a + b * len;
  };
  st.diag_pos.resize(static_cast<std::size_t>(np * d * d));
  st.adj_pos.resize(neighbours.size() * static_cast<std::size_t>(d * d));
  st.adj_pos_t.resize(st.adj_pos.size());
  for (Index p = 0; p < np; ++p) {
    block(p, p, st.diag_pos, static_cast<std::size_t>(p * d * d));
    for (Index e = start[static_cast<std::size_t>(p)]; e < start[static_cast<std::size_t>(p) + 1];
         ++e) {
      const Index q = neighbours[static_cast<std::size_t>(e)].other;
      block(p, q, st.adj_pos, static_cast<std::size_t>(e * d * d));
      // The transposed block (rows of q, columns of p), element [a][b] at (q a, p b).
      block(q, p, st.adj_pos_t, static_cast<std::size_t>(e * d * d));
    }
  }
  if (with_faces) {
    st.face_pos.resize(9 * triangles_.size());
    for (std::size_t t = 0; t < triangles_.size(); ++t) {
      const Triangle& tr = triangles_[t];
      const Index v[3] = {tr.a, tr.b, tr.c};
      for (int p = 0; p < 3; ++p)
        for (int q = 0; q < 3; ++q) st.face_pos[9 * t + 3 * p + q] = position(d * v[p], d * v[q]);
    }
  }
  return st;
}

// ---------------------------------------------------------------------------------------------
// Forces.

namespace {

// The spring kernel of the right-hand side (see the header comment): springs [e0, e1) add
// f_i += c r and f_j -= c r, r = x_j - x_i, c = k (l - L)/l (+ c_d (u·r)/l² with a dashpot).
// kBlock springs at a time: first their c r in a loop without dependences between springs
// (`omp simd`: the compiler evaluates several springs per SIMD lane, gathering the end points'
// coordinates), then the additions in spring order, so the sums run in the same order as a
// one-spring-at-a-time loop and do not depend on the vector width.
struct SpringArgs {
  const std::int32_t* i;  // first end's first coordinate: D × point
  const std::int32_t* j;  // second end's
  const std::int32_t* kind;
  const double* k;
  const double* rest;
  const double* damping;         // nullptr without dashpots
  const std::uint8_t* implicit;  // per spring; nullptr: add every spring
  std::uint8_t want;             // with `implicit`: add the springs with implicit[e] == want
  const detail::SpringRun* runs;
};

constexpr int kBlock = 128;

template <int D, bool Dashpots>
[[gnu::always_inline]] inline void spring_range_impl(const SpringArgs& s, Index e0, Index e1,
                                                     const double* x, const double* v, double* f) {
  alignas(64) double cr[D][kBlock];
  for (Index b0 = e0; b0 < e1; b0 += kBlock) {
    const int nb = static_cast<int>(std::min<Index>(kBlock, e1 - b0));
    const std::int32_t* si = s.i + b0;
    const std::int32_t* sj = s.j + b0;
    const std::int32_t* kind = s.kind + b0;
#pragma omp simd
    for (int b = 0; b < nb; ++b) {
      const Index pi = si[b], pj = sj[b];
      double r[D], l2 = 0.0;
      for (int c = 0; c < D; ++c) {
        r[c] = x[pj + c] - x[pi + c];
        l2 += r[c] * r[c];
      }
      const double l = std::sqrt(l2);
      double coef = s.k[kind[b]] * (l - s.rest[kind[b]]) / l;
      if constexpr (Dashpots) {
        double ur = 0.0;
        for (int c = 0; c < D; ++c) ur += (v[pj + c] - v[pi + c]) * r[c];
        const double cd = s.damping[b0 + b];
        coef += cd != 0.0 ? cd * ur / l2 : 0.0;
      }
      for (int c = 0; c < D; ++c) cr[c][b] = coef * r[c];
    }
    // The additions, in spring order. Consecutive springs with the same first end (a point's
    // springs are listed together) keep f_i in registers: the same additions in the same order
    // as through memory, without waiting for each store to reach the next load.
    Index cur = -1;
    double fc[D] = {};
    for (int b = 0; b < nb; ++b) {
      if (s.implicit && s.implicit[b0 + b] != s.want) continue;
      const Index pi = si[b];
      if (pi != cur) {
        if (cur >= 0)
          for (int c = 0; c < D; ++c) f[cur + c] = fc[c];
        cur = pi;
        for (int c = 0; c < D; ++c) fc[c] = f[cur + c];
      }
      double* fj = f + sj[b];
      for (int c = 0; c < D; ++c) {
        fc[c] += cr[c][b];
        fj[c] -= cr[c][b];
      }
    }
    if (cur >= 0)
      for (int c = 0; c < D; ++c) f[cur + c] = fc[c];
  }
}

// A run (detail::SpringRun): the same c r as spring_range_impl, from contiguous coordinates
// (the compiler vectorises the stride-D loads and stores with permutes), then f_i += c r for
// the block's springs and f_j -= c r, each a loop over distinct points. Every point's additions
// run in an order fixed by the packing, whatever the vector width.
template <int D, bool Dashpots>
[[gnu::always_inline]] inline void spring_run_impl(const SpringArgs& s,
                                                   const detail::SpringRun& run, const double* x,
                                                   const double* v, double* f) {
  if (s.implicit && run.implicit != s.want) return;
  const double k = s.k[run.kind], rest = s.rest[run.kind];
  alignas(64) double cr[D][kBlock];
  for (Index b0 = 0; b0 < run.n; b0 += kBlock) {
    const int nb = static_cast<int>(std::min<Index>(kBlock, run.n - b0));
    const Index oi = run.i + D * b0, oj = run.j + D * b0;
    const double* xi = x + oi;
    const double* xj = x + oj;
#pragma omp simd
    for (int b = 0; b < nb; ++b) {
      double r[D], l2 = 0.0;
      for (int c = 0; c < D; ++c) {
        r[c] = xj[D * b + c] - xi[D * b + c];
        l2 += r[c] * r[c];
      }
      const double l = std::sqrt(l2);
      double coef = k * (l - rest) / l;
      if constexpr (Dashpots) {
        double ur = 0.0;
        for (int c = 0; c < D; ++c) ur += (v[oj + D * b + c] - v[oi + D * b + c]) * r[c];
        const double cd = s.damping[run.first + b0 + b];
        coef += cd != 0.0 ? cd * ur / l2 : 0.0;
      }
      for (int c = 0; c < D; ++c) cr[c][b] = coef * r[c];
    }
    double* fi = f + oi;
#pragma omp simd
    for (int b = 0; b < nb; ++b)
      for (int c = 0; c < D; ++c) fi[D * b + c] += cr[c][b];
    double* fj = f + oj;
#pragma omp simd
    for (int b = 0; b < nb; ++b)
      for (int c = 0; c < D; ++c) fj[D * b + c] -= cr[c][b];
  }
}

// Group G of the packing: its runs, then its loose springs.
template <int D, bool Dashpots>
[[gnu::always_inline]] inline void spring_group_impl(const SpringArgs& s, Index r0, Index r1,
                                                     Index e0, Index e1, const double* x,
                                                     const double* v, double* f) {
  for (Index r = r0; r < r1; ++r) spring_run_impl<D, Dashpots>(s, s.runs[r], x, v, f);
  spring_range_impl<D, Dashpots>(s, e0, e1, x, v, f);
}

template <int D>
void spring_group_portable(const SpringArgs& s, Index r0, Index r1, Index e0, Index e1,
                           const double* x, const double* v, double* f) {
  if (s.damping)
    spring_group_impl<D, true>(s, r0, r1, e0, e1, x, v, f);
  else
    spring_group_impl<D, false>(s, r0, r1, e0, e1, x, v, f);
}

// A build for AVX2 or better (-march, e.g. STIFFBENCH_NATIVE) uses the portable kernel as is.
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__AVX2__)
#define STIFFBENCH_SPRING_AVX2_DISPATCH 1
// The same kernel compiled for AVX2 (4 springs per vector; GCC loads a loose spring's end points
// lane by lane: its vgatherdpd version measured 25% slower on the project's AMD EPYC), chosen at
// run time when the processor has it. With -ffp-contract=off (CMakeLists.txt) the compiler fuses
// no multiply-add, and sqrt and division are correctly rounded, so both versions give the same
// bits.
template <int D>
__attribute__((target("avx2"))) void spring_group_avx2(const SpringArgs& s, Index r0, Index r1,
                                                       Index e0, Index e1, const double* x,
                                                       const double* v, double* f) {
  if (s.damping)
    spring_group_impl<D, true>(s, r0, r1, e0, e1, x, v, f);
  else
    spring_group_impl<D, false>(s, r0, r1, e0, e1, x, v, f);
}
#endif

#if defined(__GNUC__) && defined(__x86_64__)
#define STIFFBENCH_SPRING_AVX512_DISPATCH 1
// A 3D run in AVX-512 (explicit intrinsics, chosen at run time on processors with AVX-512F, in
// any build). The compiler's version of spring_run_impl spends most of its time on permutes: it
// transposes each spring's interleaved (x, y, z) into one vector per coordinate on the way in, and
// back on the way out. Here eight springs' coordinates are three contiguous 512-bit loads per
// end; r = x_j - x_i and r² stay interleaved, and only two things are permuted: the squares into
// one vector per coordinate (two two-source permutes each) for l², and the eight coefficients
// back into the interleaved order of r (one permute per vector). c r is stored interleaved, so
// the additions f_i += c r and f_j -= c r are contiguous vector loops over the block. Every
// operation is spring_run_impl's, in its order (l² = (r_x² + r_y²) + r_z², (u·r) summed from
// +0.0, the additions of f_i before those of f_j within a block of kBlock springs), and sqrt and
// division are correctly rounded, so the bits are the portable kernel's
// (tests/models/test_spring_kernel.cpp compares the builds). The masked forms of sqrt and of the
// one-source permute (all lanes kept) stand for the plain ones, whose GCC 12 versions trip
// -Wmaybe-uninitialized inside avx512fintrin.h (GCC bug 105593).
alignas(64) constexpr std::int64_t kPermIdx[8][8] = {
    {0, 3, 6, 9, 12, 15, 0, 0},  // x components from the first two vectors
    {0, 1, 2, 3, 4, 5, 10, 13},  // ... and the third
    {1, 4, 7, 10, 13, 0, 0, 0},  // y
    {0, 1, 2, 3, 4, 8, 11, 14},
    {2, 5, 8, 11, 14, 0, 0, 0},  // z
    {0, 1, 2, 3, 4, 9, 12, 15},
    {0, 0, 0, 1, 1, 1, 2, 2},  // coefficients 0..7 spread over interleaved elements 0..7
    {2, 3, 3, 3, 4, 4, 4, 5},  // ... 8..15
};
alignas(64) constexpr std::int64_t kSpreadLast[8] = {5, 5, 6, 6, 6, 7, 7, 7};  // ... 16..23

// Σ_c of interleaved triples q0 q1 q2 (eight springs' (x, y, z)), as ((start + q_x) + q_y) + q_z.
__attribute__((target("avx512f"))) inline __m512d sum_triples(__m512d q0, __m512d q1, __m512d q2,
                                                              __m512d start) {
  __m512i idx[6];
  for (int row = 0; row < 6; ++row) idx[row] = _mm512_load_si512(kPermIdx[row]);
  const __m512d qx = _mm512_permutex2var_pd(_mm512_permutex2var_pd(q0, idx[0], q1), idx[1], q2);
  const __m512d qy = _mm512_permutex2var_pd(_mm512_permutex2var_pd(q0, idx[2], q1), idx[3], q2);
  const __m512d qz = _mm512_permutex2var_pd(_mm512_permutex2var_pd(q0, idx[4], q1), idx[5], q2);
  return _mm512_add_pd(_mm512_add_pd(_mm512_add_pd(start, qx), qy), qz);
}

// One spring of a run, spring_run_impl's operations, into the interleaved cr.
template <bool Dashpots>
[[gnu::always_inline]] inline void run_spring_scalar(const double* xi, const double* xj,
                                                     const double* vi, const double* vj, double k,
                                                     double rest, double cd, double* cr) {
  double r[3], l2 = 0.0;
  for (int c = 0; c < 3; ++c) {
    r[c] = xj[c] - xi[c];
    l2 += r[c] * r[c];
  }
  const double l = std::sqrt(l2);
  double coef = k * (l - rest) / l;
  if constexpr (Dashpots) {
    double ur = 0.0;
    for (int c = 0; c < 3; ++c) ur += (vj[c] - vi[c]) * r[c];
    coef += cd != 0.0 ? cd * ur / l2 : 0.0;
  }
  for (int c = 0; c < 3; ++c) cr[c] = coef * r[c];
}

// dst[t] += c[t] (Minus: -=) for t < n, eight at a time.
template <bool Minus>
__attribute__((target("avx512f"))) inline void add_interleaved(double* dst, const double* c,
                                                               int n) {
  int t = 0;
  for (; t + 8 <= n; t += 8) {
    const __m512d a = _mm512_loadu_pd(dst + t), b = _mm512_load_pd(c + t);
    _mm512_storeu_pd(dst + t, Minus ? _mm512_sub_pd(a, b) : _mm512_add_pd(a, b));
  }
  if (t < n) {
    const auto m = static_cast<__mmask8>((1u << (n - t)) - 1u);
    const __m512d a = _mm512_maskz_loadu_pd(m, dst + t), b = _mm512_maskz_load_pd(m, c + t);
    _mm512_mask_storeu_pd(dst + t, m, Minus ? _mm512_sub_pd(a, b) : _mm512_add_pd(a, b));
  }
}

template <bool Dashpots>
__attribute__((target("avx512f"))) void spring_run_avx512(const SpringArgs& s,
                                                          const detail::SpringRun& run,
                                                          const double* x, const double* v,
                                                          double* f) {
  if (s.implicit && run.implicit != s.want) return;
  const double k = s.k[run.kind], rest = s.rest[run.kind];
  const __m512d vk = _mm512_set1_pd(k), vrest = _mm512_set1_pd(rest), zero = _mm512_setzero_pd();
  const __m512i spread0 = _mm512_load_si512(kPermIdx[6]), spread1 = _mm512_load_si512(kPermIdx[7]),
                spread2 = _mm512_load_si512(kSpreadLast);
  alignas(64) double cr[3 * kBlock];
  for (Index b0 = 0; b0 < run.n; b0 += kBlock) {
    const int nb = static_cast<int>(std::min<Index>(kBlock, run.n - b0));
    const Index oi = run.i + 3 * b0, oj = run.j + 3 * b0;
    const double* xi = x + oi;
    const double* xj = x + oj;
    const double* cd = Dashpots ? s.damping + run.first + b0 : nullptr;
    int b = 0;
    for (; b + 8 <= nb; b += 8) {
      const double* pi = xi + 3 * b;
      const double* pj = xj + 3 * b;
      const __m512d r0 = _mm512_sub_pd(_mm512_loadu_pd(pj), _mm512_loadu_pd(pi));
      const __m512d r1 = _mm512_sub_pd(_mm512_loadu_pd(pj + 8), _mm512_loadu_pd(pi + 8));
      const __m512d r2 = _mm512_sub_pd(_mm512_loadu_pd(pj + 16), _mm512_loadu_pd(pi + 16));
      // l² from +0.0 adds nothing to spring_run_impl's sum: r_x² is never -0.0.
      const __m512d l2 =
          sum_triples(_mm512_mul_pd(r0, r0), _mm512_mul_pd(r1, r1), _mm512_mul_pd(r2, r2), zero);
      const __m512d l = _mm512_maskz_sqrt_pd(0xFF, l2);
      __m512d coef = _mm512_div_pd(_mm512_mul_pd(vk, _mm512_sub_pd(l, vrest)), l);
      if constexpr (Dashpots) {
        const double* ui = v + oi + 3 * b;
        const double* uj = v + oj + 3 * b;
        const __m512d u0 = _mm512_sub_pd(_mm512_loadu_pd(uj), _mm512_loadu_pd(ui));
        const __m512d u1 = _mm512_sub_pd(_mm512_loadu_pd(uj + 8), _mm512_loadu_pd(ui + 8));
        const __m512d u2 = _mm512_sub_pd(_mm512_loadu_pd(uj + 16), _mm512_loadu_pd(ui + 16));
        const __m512d ur =
            sum_triples(_mm512_mul_pd(u0, r0), _mm512_mul_pd(u1, r1), _mm512_mul_pd(u2, r2), zero);
        const __m512d c = _mm512_loadu_pd(cd + b);
        const __mmask8 has = _mm512_cmp_pd_mask(c, zero, _CMP_NEQ_UQ);
        coef =
            _mm512_add_pd(coef, _mm512_maskz_mov_pd(has, _mm512_div_pd(_mm512_mul_pd(c, ur), l2)));
      }
      double* out = cr + 3 * b;
      _mm512_store_pd(out, _mm512_mul_pd(_mm512_maskz_permutexvar_pd(0xFF, spread0, coef), r0));
      _mm512_store_pd(out + 8, _mm512_mul_pd(_mm512_maskz_permutexvar_pd(0xFF, spread1, coef), r1));
      _mm512_store_pd(out + 16,
                      _mm512_mul_pd(_mm512_maskz_permutexvar_pd(0xFF, spread2, coef), r2));
    }
    for (; b < nb; ++b)
      run_spring_scalar<Dashpots>(xi + 3 * b, xj + 3 * b, v + oi + 3 * b, v + oj + 3 * b, k, rest,
                                  Dashpots ? cd[b] : 0.0, cr + 3 * b);
    // f_i += c r over the block, then f_j -= c r (each a set of distinct points).
    add_interleaved<false>(f + oi, cr, 3 * nb);
    add_interleaved<true>(f + oj, cr, 3 * nb);
  }
}

// The runs [r0, r1) of a group in 3D on an AVX-512 processor (its loose springs: spring_group).
__attribute__((target("avx512f"))) void spring_runs_avx512(const SpringArgs& s, Index r0, Index r1,
                                                           const double* x, const double* v,
                                                           double* f) {
  for (Index r = r0; r < r1; ++r) {
    if (s.damping)
      spring_run_avx512<true>(s, s.runs[r], x, v, f);
    else
      spring_run_avx512<false>(s, s.runs[r], x, v, f);
  }
}
#endif

// The widest build of the kernel in use (MassSpringNetwork::kernel_isa), at most the processor's
// and at most the process-wide limit set by MassSpringNetwork::limit_kernel_isa.
std::atomic<int> g_isa_limit{static_cast<int>(SpringKernelIsa::avx512)};

SpringKernelIsa processor_isa() {
  static const SpringKernelIsa isa = [] {
#if defined(STIFFBENCH_SPRING_AVX512_DISPATCH)
    if (__builtin_cpu_supports("avx512f")) return SpringKernelIsa::avx512;
#endif
#if defined(STIFFBENCH_SPRING_AVX2_DISPATCH)
    if (__builtin_cpu_supports("avx2")) return SpringKernelIsa::avx2;
#elif defined(__AVX2__)
    return SpringKernelIsa::avx2;  // the portable build is compiled for AVX2 or better
#endif
    return SpringKernelIsa::portable;
  }();
  return isa;
}

SpringKernelIsa kernel_isa_in_use() {
  return static_cast<SpringKernelIsa>(
      std::min(static_cast<int>(processor_isa()), g_isa_limit.load(std::memory_order_relaxed)));
}

template <int D>
void spring_group(const SpringArgs& s, Index r0, Index r1, Index e0, Index e1, const double* x,
                  const double* v, double* f, SpringKernelIsa isa) {
#ifdef STIFFBENCH_SPRING_AVX512_DISPATCH
  if (D == 3 && isa == SpringKernelIsa::avx512) {
    spring_runs_avx512(s, r0, r1, x, v, f);
    r0 = r1;  // the loose springs below
  }
#endif
#ifdef STIFFBENCH_SPRING_AVX2_DISPATCH
  if (isa != SpringKernelIsa::portable) {
    spring_group_avx2<D>(s, r0, r1, e0, e1, x, v, f);
    return;
  }
#endif
  (void)isa;
  spring_group_portable<D>(s, r0, r1, e0, e1, x, v, f);
}

// Points [p0, p1): force sums into accelerations, a = g + (f - γ v)/m (Springs: f/m only), 0 for
// pinned points, in a loop the compiler vectorises (the pinned select is a bit mask).
template <int D, bool Springs>
void finish_points(double* __restrict a, const double* __restrict v, const double* __restrict mass,
                   const std::uint8_t* __restrict pinned, const double* g, double gamma, Index p0,
                   Index p1) {
  const double g0 = g[0], g1 = D > 1 ? g[1] : 0.0, g2 = D > 2 ? g[2] : 0.0;
#pragma omp simd
  for (Index p = p0; p < p1; ++p) {
    const std::uint64_t keep = std::uint64_t{0} - static_cast<std::uint64_t>(pinned[p] == 0);
    const double m = mass[p];
#pragma GCC unroll 3
    for (int c = 0; c < D; ++c) {
      const double gc = c == 0 ? g0 : c == 1 ? g1 : g2;
      const double ac = Springs ? a[D * p + c] / m : gc + (a[D * p + c] - gamma * v[D * p + c]) / m;
      a[D * p + c] = std::bit_cast<double>(std::bit_cast<std::uint64_t>(ac) & keep);
    }
  }
}

}  // namespace

template <int D, MassSpringNetwork::Part P>
void MassSpringNetwork::acceleration_impl(const double* x, const double* v, double* a,
                                          const DofRangeFn* done, const ChainCall* call) const {
  const double gamma = opt_.point_damping;
  const Index np = num_points();
  const Index parts = rhs_parts_;
  const RhsSprings& rs = rhs_springs_;
  const SpringKernelIsa isa = kernel_isa_in_use();
  // A part of the split adds its own springs only (springs: all in a_I, none in a_E).
  const SpringArgs args{rs.i.data(),
                        rs.j.data(),
                        rs.kind.data(),
                        rs.k.data(),
                        rs.rest.data(),
                        has_dashpots_ ? rs.damping.data() : nullptr,
                        P == Part::all ? nullptr : packed_implicit_.data(),
                        static_cast<std::uint8_t>(P == Part::implicit_part ? 1 : 0),
                        runs_.data()};
  // Group G of the packing (its runs, then its loose springs).
  const auto springs_of = [&](Index G) {
    const auto u = static_cast<std::size_t>(G);
    spring_group<D>(args, group_runs_[u], group_runs_[u + 1], group_loose_[u], group_start_[u + 1],
                    x, v, a, isa);
  };
  // a first holds the force sums.
  // 1. The springs between partitions, group by group in a fixed order (the groups of one
  //    parity touch disjoint points); the even groups first clear their points (below).
  const auto group = [&](Index g) { springs_of(parts + g); };
  // 2. Each partition of points (contiguous index ranges, a count fixed by the network's size,
  //    not by the threads) adds its interior springs, then turns its points' force sums into
  //    accelerations while they are in cache: a = g + (f - γ v)/m; pinned points do not move.
  const double* mass = point_mass_.data();
  const std::uint8_t* pinned = pinned_.data();
  double g[D];
  for (int c = 0; c < D; ++c) g[c] = opt_.gravity[static_cast<std::size_t>(c)];
  // With done (acceleration_in_ranges, no drag): partition q's dofs are final once its points
  // are finished, and nothing after reads x or v there (the later partitions' springs have both
  // ends in their own partitions).
  const auto partition = [&](Index q) {
    const Index a0 = late_clear_[2 * static_cast<std::size_t>(q)],
                a1 = late_clear_[2 * static_cast<std::size_t>(q) + 1];
    std::fill(a + D * a0, a + D * a1, 0.0);
    springs_of(q);
    finish_points<D, P == Part::implicit_part>(a, v, mass, pinned, g, gamma, np * q / parts,
                                               np * (q + 1) / parts);
    if (done) (*done)(D * (np * q / parts), D * (np * (q + 1) / parts));
  };
  const Index ne = even_groups_, no = odd_groups_;
  // Even group e touches the points of partitions 2e and 2e + 1 only: it clears them just before
  // its springs (but for each partition's late-cleared range, which no group touches). Partitions
  // no even group covers (an odd count: only the single partition of a small network) are cleared
  // in the same stage.
  const auto clear = [&](Index q) {  // all but the points cleared late (partition, above)
    const Index a0 = late_clear_[2 * static_cast<std::size_t>(q)],
                a1 = late_clear_[2 * static_cast<std::size_t>(q) + 1];
    std::fill(a + D * (np * q / parts), a + D * a0, 0.0);
    std::fill(a + D * a1, a + D * (np * (q + 1) / parts), 0.0);
  };
  const auto first_stage = [&](Index e) {
    if (e < ne) {
      clear(2 * e);
      clear(2 * e + 1);
      group(e);
    } else {
      clear(2 * ne + (e - ne));
    }
  };
  if (call) {  // one piece of a chained evaluation (Chain)
    switch (call->what) {
      case ChainCall::What::clear:
        return clear(call->q);
      case ChainCall::What::link:  // the group of the springs between q and q + 1
        return group(call->q % 2 == 0 ? call->q / 2 : ne + call->q / 2);
      case ChainCall::What::finish:
        return partition(call->q);
    }
    return;
  }
  const Index first = ne + (parts - 2 * ne);
  const bool rest = group_start_[static_cast<std::size_t>(parts + ne + no)] <
                    group_start_[static_cast<std::size_t>(parts + ne + no) + 1];
  if (parallel()) {
    // One parallel region, its stages separated by the work-sharing loops' barriers.
#pragma omp parallel
    {
#pragma omp for schedule(static)
      for (Index e = 0; e < first; ++e) first_stage(e);
#pragma omp for schedule(static)
      for (Index e = ne; e < ne + no; ++e) group(e);
      if (rest) {  // the same on every thread
#pragma omp single
        group(ne + no);
      }
#pragma omp for schedule(static)
      for (Index q = 0; q < parts; ++q) partition(q);
    }
  } else {
    for (Index e = 0; e < first; ++e) first_stage(e);
    for (Index e = ne; e <= ne + no; ++e) group(e);
    for (Index q = 0; q < parts; ++q) partition(q);
  }
  // Air drag is in a_E (and in a); the constructor allows it in 3D only.
  if (P != Part::implicit_part && drag()) add_drag(x, v, a);
}

const char* to_string(SpringKernelIsa isa) {
  switch (isa) {
    case SpringKernelIsa::portable:
      return "portable";
    case SpringKernelIsa::avx2:
      return "avx2";
    case SpringKernelIsa::avx512:
      return "avx512";
  }
  return "?";
}

SpringKernelIsa MassSpringNetwork::kernel_isa() { return kernel_isa_in_use(); }

void MassSpringNetwork::limit_kernel_isa(SpringKernelIsa widest) {
  g_isa_limit.store(static_cast<int>(widest), std::memory_order_relaxed);
}

void MassSpringNetwork::eval_acceleration(double, CVecRef x, CVecRef v, VecRef a) const {
  detail::with_dim<1, 3>(dim_, [&](auto dim) {
    acceleration_impl<decltype(dim)::value, Part::all>(x.data(), v.data(), a.data(), nullptr);
  });
}

void MassSpringNetwork::eval_acceleration_in_ranges(double t, CVecRef x, CVecRef v, VecRef a,
                                                    DofRangeFn done) const {
  // Air drag is added after all partitions: then the default (done after the whole a).
  if (drag()) return MechanicalSystem::eval_acceleration_in_ranges(t, x, v, a, done);
  detail::with_dim<1, 3>(dim_, [&](auto dim) {
    acceleration_impl<decltype(dim)::value, Part::all>(x.data(), v.data(), a.data(), &done);
  });
}

void MassSpringNetwork::Chain::call(ChainCall::What what, Index q, const double* x, const double* v,
                                    double* a) const {
  const ChainCall c{what, q};
  detail::with_dim<1, 3>(net_.dim_, [&](auto dim) {
    net_.acceleration_impl<decltype(dim)::value, Part::all>(x, v, a, nullptr, &c);
  });
}

void MassSpringNetwork::Chain::clear(Index q, VecRef a) const {
  call(ChainCall::What::clear, q, nullptr, nullptr, a.data());
}

void MassSpringNetwork::Chain::link(Index q, double, CVecRef x, CVecRef v, VecRef a) const {
  call(ChainCall::What::link, q, x.data(), v.data(), a.data());
}

void MassSpringNetwork::Chain::finish(Index q, double, CVecRef x, CVecRef v, VecRef a) const {
  call(ChainCall::What::finish, q, x.data(), v.data(), a.data());
}

void MassSpringNetwork::eval_acceleration_explicit_part(double, CVecRef x, CVecRef v,
                                                        VecRef a) const {
  require_input(has_imex_split(), name_ + ": no split (parameter split=none)");
  detail::with_dim<1, 3>(dim_, [&](auto dim) {
    acceleration_impl<decltype(dim)::value, Part::explicit_part>(x.data(), v.data(), a.data(),
                                                                 nullptr);
  });
}

void MassSpringNetwork::eval_acceleration_implicit_part(double, CVecRef x, CVecRef v,
                                                        VecRef a) const {
  require_input(has_imex_split(), name_ + ": no split (parameter split=none)");
  detail::with_dim<1, 3>(dim_, [&](auto dim) {
    acceleration_impl<decltype(dim)::value, Part::implicit_part>(x.data(), v.data(), a.data(),
                                                                 nullptr);
  });
}

// ---------------------------------------------------------------------------------------------
// Jacobian blocks.
//
// Derivation of the dashpot's position derivative: f_i = c s d with s = u·d, u = v_j - v_i,
// d = (x_j - x_i)/l. Then ∂f_i/∂d = c (d uᵀ + s I) and ∂d/∂x_j = (I - d dᵀ)/l, so
//   ∂f_i/∂x_j = (c/l)(d uᵀ + s I)(I - d dᵀ) = (c/l)[d (u - s d)ᵀ + s (I - d dᵀ)] = J_c,
// and ∂f_i/∂x_i = -J_c because d depends on x_j - x_i only. ∂f_i/∂v_j = c d dᵀ = -∂f_i/∂v_i.

template <int D>
void MassSpringNetwork::blocks_impl(const Structure& st, double gamma, const double* x,
                                    const double* v, double* k_values, double* d_values) const {
  const bool dd_only = opt_.compressed_dd_only;
  const Index* start = st.adjacency->start.data();
  const SpringNeighbour* nb = st.adjacency->neighbours.data();
  const MassPoint* pts = points_.data();
  const Index* dpos = st.diag_pos.data();
  const Index* apos = st.adj_pos.data();
  // Without dashpots each spring's block J_s is symmetric and the same from both ends, so point
  // p can fill its own column block instead of its row block: K_qp = J_s / m_q (0 for a pinned
  // q), a contiguous range of the column-major storage. With dashpots (J_c is not symmetric)
  // point p fills its rows.
  const bool by_column = !st.dashpots && !d_values;
  const Index* tpos = st.adj_pos_t.data();
  const double* inv_mass = inv_mass_.data();
  if (by_column && k_values) {
    for_points(num_points(), parallel(), [&](Index p) {
      const double* xp = x + D * p;
      for (Index e = start[p]; e < start[p + 1]; ++e)
        for (int q = 0; q < D * D; ++q) k_values[tpos[e * D * D + q]] = 0.0;
      double kd[D][D] = {};
      for (Index e = start[p]; e < start[p + 1]; ++e) {
        const SpringNeighbour& s = nb[e];
        const double* xq = x + D * s.other;
        double dir[D], l2 = 0.0;
        for (int c = 0; c < D; ++c) {
          dir[c] = xq[c] - xp[c];
          l2 += dir[c] * dir[c];
        }
        const double l = std::sqrt(l2);
        for (int c = 0; c < D; ++c) dir[c] /= l;
        const double across = (dd_only && l < s.rest) ? 0.0 : s.k * (1.0 - s.rest / l);
        const double along = s.k - across;
        const double wq = inv_mass[s.other];
        const Index* pos = tpos + e * D * D;
        for (int a = 0; a < D; ++a)
          for (int b = 0; b < D; ++b) {
            const double j = along * dir[a] * dir[b] + (a == b ? across : 0.0);
            k_values[pos[a * D + b]] += j * wq;
            kd[a][b] -= j;
          }
      }
      const Index* pos = dpos + p * D * D;
      const double wp = inv_mass[p];  // 0 for a pinned point: zero rows
      for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b) k_values[pos[a * D + b]] = kd[a][b] * wp;
    });
    return;
  }
  for_points(num_points(), parallel(), [&](Index p) {
    const MassPoint& pt = pts[p];
    // This point's rows: cleared here (in parallel, no pass over the whole matrix), then summed.
    for (Index e = start[p]; e < start[p + 1]; ++e)
      for (int q = 0; q < D * D; ++q) {
        if (k_values) k_values[apos[e * D * D + q]] = 0.0;
        if (d_values) d_values[apos[e * D * D + q]] = 0.0;
      }
    if (pt.pinned) {  // zero rows
      for (int q = 0; q < D * D; ++q) {
        if (k_values) k_values[dpos[p * D * D + q]] = 0.0;
        if (d_values) d_values[dpos[p * D * D + q]] = 0.0;
      }
      return;
    }
    const double inv_m = 1.0 / pt.mass;
    const double* xp = x + D * p;
    const double* vp = v + D * p;
    double kd[D][D] = {}, dd[D][D] = {};  // diagonal blocks, accumulated
    for (Index e = start[p]; e < start[p + 1]; ++e) {
      const SpringNeighbour& s = nb[e];
      const double* xq = x + D * s.other;
      double dir[D], l2 = 0.0;
      for (int c = 0; c < D; ++c) {
        dir[c] = xq[c] - xp[c];
        l2 += dir[c] * dir[c];
      }
      const double l = std::sqrt(l2);
      for (int c = 0; c < D; ++c) dir[c] /= l;
      // J_s = k [d dᵀ + (1 - L/l)(I - d dᵀ)] = k (L/l) d dᵀ + k (1 - L/l) I.
      const double across = (dd_only && l < s.rest) ? 0.0 : s.k * (1.0 - s.rest / l);
      const double along = s.k - across;  // coefficient of d dᵀ: k·L/l, or k when dropped
      double jk[D][D], jd[D][D];
      for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b) {
          jk[a][b] = along * dir[a] * dir[b] + (a == b ? across : 0.0);
          jd[a][b] = 0.0;
        }
      if (s.damping != 0.0) {
        const double* vq = v + D * s.other;
        double u[D], sd = 0.0;
        for (int c = 0; c < D; ++c) {
          u[c] = vq[c] - vp[c];
          sd += u[c] * dir[c];
        }
        const double cl = s.damping / l;
        for (int a = 0; a < D; ++a)
          for (int b = 0; b < D; ++b) {
            // J_c = (c/l)[d (u - s d)ᵀ + s (I - d dᵀ)];  D_c = c d dᵀ.
            jk[a][b] += cl * (dir[a] * (u[b] - sd * dir[b]) +
                              sd * ((a == b ? 1.0 : 0.0) - dir[a] * dir[b]));
            jd[a][b] = s.damping * dir[a] * dir[b];
          }
      }
      const Index* pos = apos + e * D * D;
      for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b) {
          if (k_values) k_values[pos[a * D + b]] += jk[a][b] * inv_m;
          if (d_values) d_values[pos[a * D + b]] += jd[a][b] * inv_m;
          kd[a][b] -= jk[a][b];
          dd[a][b] -= jd[a][b];
        }
    }
    const Index* pos = dpos + p * D * D;
    for (int a = 0; a < D; ++a)
      for (int b = 0; b < D; ++b) {
        if (k_values) k_values[pos[a * D + b]] = kd[a][b] * inv_m;
        if (d_values) d_values[pos[a * D + b]] = (dd[a][b] - (a == b ? gamma : 0.0)) * inv_m;
      }
  });
}

void MassSpringNetwork::fill_blocks(const Structure& st, double gamma, bool with_drag, CVecRef x,
                                    CVecRef v, SparseMat* k, SparseMat* d) const {
  // A matrix that already has this pattern (same size and number of nonzeros, compressed: a
  // previous result of this network) keeps its storage; only the values are written. Without
  // dashpots D = -(γ/m) I is diagonal and gets a diagonal pattern.
  const auto ensure = [](SparseMat* m, const SparseMat& pattern) {
    if (!m) return;
    if (m->rows() != pattern.rows() || m->cols() != pattern.cols() ||
        m->nonZeros() != pattern.nonZeros() || !m->isCompressed())
      *m = pattern;
  };
  with_drag = with_drag && drag();
  const bool full_d = st.dashpots || with_drag;  // D on K's pattern
  ensure(k, st.pattern);
  ensure(d, full_d ? st.pattern : st.diag_pattern);
  double* kv = k ? k->valuePtr() : nullptr;
  double* dv = d && full_d ? d->valuePtr() : nullptr;
  if (kv || dv)
    detail::with_dim<1, 3>(dim_, [&](auto dim) {
      blocks_impl<decltype(dim)::value>(st, gamma, x.data(), v.data(), kv, dv);
    });
  if (with_drag) add_drag_blocks(st, x.data(), v.data(), kv, dv);
  if (d && !full_d) {
    double* dd = d->valuePtr();
    for (Index p = 0; p < num_points(); ++p)
      for (int c = 0; c < dim_; ++c)
        dd[dim_ * p + c] = -gamma * inv_mass_[static_cast<std::size_t>(p)];
  }
}

void MassSpringNetwork::stiffness_block(double, CVecRef x, CVecRef v, SparseMat& k) const {
  ensure_structure();
  fill_blocks(structure_, opt_.point_damping, true, x, v, &k, nullptr);
}

void MassSpringNetwork::damping_block(double, CVecRef x, CVecRef v, SparseMat& d) const {
  ensure_structure();
  fill_blocks(structure_, opt_.point_damping, true, x, v, nullptr, &d);
}

void MassSpringNetwork::force_jacobians(double, CVecRef x, CVecRef v, SparseMat& k,
                                        SparseMat& d) const {
  ensure_structure();
  fill_blocks(structure_, opt_.point_damping, true, x, v, &k, &d);
}

// ---------------------------------------------------------------------------------------------
// Air drag (see the header comment for the force and its derivatives).

namespace {

// One triangle's drag at (x, v): N, v̄, u = v̄·N, w = 1/|N|² (0 for a triangle of zero area) and
// the force F = -β u|u| w N, β = β_d/2.
struct FaceDrag {
  double n[3], vbar[3], u, w, f[3];
};

FaceDrag face_drag(const double* x, const double* v, const Triangle& t, double beta) {
  FaceDrag r{};
  const double* xa = x + 3 * t.a;
  const double* xb = x + 3 * t.b;
  const double* xc = x + 3 * t.c;
  const double e1[3] = {xb[0] - xa[0], xb[1] - xa[1], xb[2] - xa[2]};
  const double e2[3] = {xc[0] - xa[0], xc[1] - xa[1], xc[2] - xa[2]};
  r.n[0] = e1[1] * e2[2] - e1[2] * e2[1];
  r.n[1] = e1[2] * e2[0] - e1[0] * e2[2];
  r.n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  const double n2 = r.n[0] * r.n[0] + r.n[1] * r.n[1] + r.n[2] * r.n[2];
  r.w = n2 > 0.0 ? 1.0 / n2 : 0.0;
  r.u = 0.0;
  for (int c = 0; c < 3; ++c) {
    r.vbar[c] = (v[3 * t.a + c] + v[3 * t.b + c] + v[3 * t.c + c]) / 3.0;
    r.u += r.vbar[c] * r.n[c];
  }
  const double scale = -beta * r.u * std::abs(r.u) * r.w;
  for (int c = 0; c < 3; ++c) r.f[c] = scale * r.n[c];
  return r;
}

}  // namespace

// The triangles' forces into face_force_, then each free point adds its triangles' shares in
// ascending triangle order: the additions of one serial pass over the triangles, for any thread
// count.
void MassSpringNetwork::add_drag(const double* x, const double* v, double* a) const {
  const double beta = 0.5 * opt_.air_drag;
  double* force = face_force_.data();
  const auto nt = static_cast<Index>(triangles_.size());
  for_points(nt, parallel(), [&](Index t) {
    const FaceDrag fd = face_drag(x, v, triangles_[static_cast<std::size_t>(t)], beta);
    for (int c = 0; c < 3; ++c) force[3 * t + c] = fd.f[c];
  });
  const Index* start = point_face_start_.data();
  const Index* faces = point_faces_.data();
  for_points(num_points(), parallel(), [&](Index p) {
    if (pinned_[static_cast<std::size_t>(p)]) return;
    const double s = inv_mass_[static_cast<std::size_t>(p)] / 3.0;
    for (Index e = start[p]; e < start[p + 1]; ++e)
      for (int c = 0; c < 3; ++c) a[3 * p + c] += s * force[3 * faces[e] + c];
  });
}

void MassSpringNetwork::add_drag_blocks(const Structure& st, const double* x, const double* v,
                                        double* k_values, double* d_values) const {
  const double beta = 0.5 * opt_.air_drag;
  const auto* outer = st.pattern.outerIndexPtr();
  for (std::size_t t = 0; t < triangles_.size(); ++t) {
    const Triangle& tr = triangles_[t];
    const Index pts[3] = {tr.a, tr.b, tr.c};
    const FaceDrag fd = face_drag(x, v, tr, beta);
    const double* n = fd.n;
    const double au = std::abs(fd.u), uau = fd.u * au, w = fd.w;
    // ∂F/∂v_q (the same for every q) and G = ∂F/∂N.
    double dv[3][3], g[3][3];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        dv[r][c] = -(2.0 * beta * au * w / 3.0) * n[r] * n[c];
        g[r][c] = -beta * (2.0 * au * w * n[r] * fd.vbar[c] + (r == c ? uau * w : 0.0) -
                           2.0 * uau * w * w * n[r] * n[c]);
      }
    // S_q = [s_q]× with s_a = e2 - e1 = x_c - x_b, s_b = -e2 = x_a - x_c, s_c = e1 = x_b - x_a.
    double side[3][3];
    for (int c = 0; c < 3; ++c) {
      side[0][c] = x[3 * tr.c + c] - x[3 * tr.b + c];
      side[1][c] = x[3 * tr.a + c] - x[3 * tr.c + c];
      side[2][c] = x[3 * tr.b + c] - x[3 * tr.a + c];
    }
    for (int qi = 0; qi < 3; ++qi) {
      const double* sq = side[qi];
      const double cross[3][3] = {{0.0, -sq[2], sq[1]}, {sq[2], 0.0, -sq[0]}, {-sq[1], sq[0], 0.0}};
      double kx[3][3];  // ∂F/∂x_q = G S_q
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
          kx[r][c] = g[r][0] * cross[0][c] + g[r][1] * cross[1][c] + g[r][2] * cross[2][c];
      const Index q = pts[qi];
      const Index len = outer[3 * q + 1] - outer[3 * q];
      for (int pi = 0; pi < 3; ++pi) {
        const Index p = pts[pi];
        if (pinned_[static_cast<std::size_t>(p)]) continue;  // zero rows
        const double s = inv_mass_[static_cast<std::size_t>(p)] / 3.0;
        const Index base = st.face_pos[9 * t + static_cast<std::size_t>(3 * pi + qi)];
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) {
            if (k_values) k_values[base + r + c * len] += s * kx[r][c];
            if (d_values) d_values[base + r + c * len] += s * dv[r][c];
          }
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Additive split (see the header comment).

std::optional<SplitInfo> MassSpringNetwork::imex_split() const {
  const std::string forces =
      drag() ? "gravity, point damping and air drag" : "gravity and point damping";
  switch (opt_.split) {
    case NetworkSplit::none:
      return std::nullopt;
    case NetworkSplit::springs:
      return SplitInfo{"springs", forces, "springs and dashpots (with x' = v)"};
    case NetworkSplit::stretch:
      return SplitInfo{"stretch", "shear and bend springs (and their dashpots), " + forces,
                       "structural springs and their dashpots (with x' = v)"};
  }
  return std::nullopt;
}

// K_I and D_I on the implicit springs' pattern, without point damping (it is explicit).
void MassSpringNetwork::implicit_force_jacobians(double, CVecRef x, CVecRef v, SparseMat& k,
                                                 SparseMat& d) const {
  require_input(has_imex_split(), name_ + ": no split (parameter split=none)");
  ensure_structure();
  fill_blocks(implicit_structure(), 0.0, false, x, v, &k, &d);
}

std::optional<SpectrumEstimate> MassSpringNetwork::explicit_part_spectrum(double, CVecRef y) const {
  if (opt_.split == NetworkSplit::springs) {
    // f_E = [0; g - γ v/m + drag/m]: ∂f_E/∂y has eigenvalues 0 and those of D_E, real and <= 0
    // (point damping: -γ/m_i); each row's sum of block norms bounds them: γ/m_p plus, per
    // triangle of p, 3 blocks of norm 2β|u|/3 (‖w N Nᵀ‖ = 1) times 1/(3 m_p).
    // Each point's triangles from the right-hand side's lists (no allocation).
    const double* x = y.data();
    const double* v = y.data() + dofs();
    const double beta = 0.5 * opt_.air_drag;
    double radius = 0.0;
    for (Index p = 0; p < num_points(); ++p) {
      double rate = opt_.point_damping;
      if (drag())
        for (Index e = point_face_start_[static_cast<std::size_t>(p)];
             e < point_face_start_[static_cast<std::size_t>(p) + 1]; ++e) {
          const Triangle& t = triangles_[static_cast<std::size_t>(point_faces_[e])];
          rate += 2.0 * beta * std::abs(face_drag(x, v, t, beta).u) / 3.0;
        }
      radius = std::max(radius, rate * inv_mass_[static_cast<std::size_t>(p)]);
    }
    return SpectrumEstimate{radius, SpectrumEstimate::Ray::negative_real};
  }
  if (opt_.split == NetworkSplit::stretch) {
    // The explicit springs alone oscillate at up to ω_max (eigenvalues ±iω of [[0, I], [K_E, 0]]);
    // the Gershgorin bound of their ω_max.
    ensure_adjacency();
    const double omega =
        StiffnessSpectrum(dim_, points_, explicit_adjacency_).omega_max_bound(y.head(dofs()));
    return SpectrumEstimate{omega, SpectrumEstimate::Ray::imaginary};
  }
  return std::nullopt;
}

std::vector<Index> MassSpringNetwork::fixed_dofs() const {
  std::vector<Index> out;
  for (Index p = 0; p < num_points(); ++p)
    if (points_[static_cast<std::size_t>(p)].pinned)
      for (int c = 0; c < dim_; ++c) out.push_back(dim_ * p + c);
  return out;
}

// ---------------------------------------------------------------------------------------------
// Observables.

double MassSpringNetwork::energy(CVecRef y) const {
  const Index n = dofs();
  double kinetic = 0.0, potential = 0.0;
  for (Index p = 0; p < num_points(); ++p) {
    const double m = points_[static_cast<std::size_t>(p)].mass;
    for (int c = 0; c < dim_; ++c) {
      const double vc = y[n + dim_ * p + c];
      kinetic += 0.5 * m * vc * vc;
      potential -= m * opt_.gravity[static_cast<std::size_t>(c)] * y[dim_ * p + c];
    }
  }
  for (const Spring& s : springs_) {
    double l2 = 0.0;
    for (int c = 0; c < dim_; ++c) {
      const double r = y[dim_ * s.j + c] - y[dim_ * s.i + c];
      l2 += r * r;
    }
    const double stretch = std::sqrt(l2) - s.rest;
    potential += 0.5 * s.k * stretch * stretch;
  }
  return kinetic + potential;
}

Vec MassSpringNetwork::linear_momentum(CVecRef y) const {
  const Index n = dofs();
  Vec p = Vec::Zero(dim_);
  for (Index q = 0; q < num_points(); ++q)
    for (int c = 0; c < dim_; ++c)
      p[c] += points_[static_cast<std::size_t>(q)].mass * y[n + dim_ * q + c];
  return p;
}

Vec MassSpringNetwork::angular_momentum(CVecRef y) const {
  const Index n = dofs();
  if (dim_ == 1) return Vec(0);
  Vec l = Vec::Zero(dim_ == 2 ? 1 : 3);
  for (Index q = 0; q < num_points(); ++q) {
    const double m = points_[static_cast<std::size_t>(q)].mass;
    const double* x = y.data() + dim_ * q;
    const double* v = y.data() + n + dim_ * q;
    if (dim_ == 2) {
      l[0] += m * (x[0] * v[1] - x[1] * v[0]);
    } else {
      l[0] += m * (x[1] * v[2] - x[2] * v[1]);
      l[1] += m * (x[2] * v[0] - x[0] * v[2]);
      l[2] += m * (x[0] * v[1] - x[1] * v[0]);
    }
  }
  return l;
}

std::vector<Invariant> MassSpringNetwork::invariants() const {
  std::vector<Invariant> out;
  const auto& g = opt_.gravity;
  const bool no_gravity = g[0] == 0.0 && g[1] == 0.0 && g[2] == 0.0;
  out.push_back(
      {"energy", [this](double, CVecRef y) { return energy(y); },
       no_gravity ? "" : "gravity's potential -m g.x is zero at x = 0, not at a rest state"});
  bool pinned = false;
  for (const MassPoint& pt : points_) pinned = pinned || pt.pinned;
  if (pinned || opt_.point_damping != 0.0 || drag()) return out;
  static const char* const axis[] = {"x", "y", "z"};
  for (int c = 0; c < dim_; ++c) {
    if (g[static_cast<std::size_t>(c)] != 0.0) continue;
    out.push_back({std::string("momentum_") + axis[c],
                   [this, c](double, CVecRef y) { return linear_momentum(y)[c]; }});
  }
  if (dim_ == 2 && no_gravity) {
    out.push_back(
        {"angular_momentum", [this](double, CVecRef y) { return angular_momentum(y)[0]; }});
  } else if (dim_ == 3) {
    for (int c = 0; c < 3; ++c) {
      // Gravity's torque M x_cm × g has no component along g: L_c is conserved when g ∥ e_c.
      bool parallel_to_axis = true;
      for (int o = 0; o < 3; ++o)
        if (o != c && g[static_cast<std::size_t>(o)] != 0.0) parallel_to_axis = false;
      if (!parallel_to_axis) continue;
      out.push_back({std::string("angular_momentum_") + axis[c],
                     [this, c](double, CVecRef y) { return angular_momentum(y)[c]; }});
    }
  }
  return out;
}

void MassSpringNetwork::exact(double t, VecRef y) const {
  if (!exact_) {
    OdeSystem::exact(t, y);
    return;
  }
  exact_(t, y);
}

// ---------------------------------------------------------------------------------------------
// Constraints (models/mass_spring/distance_constraints.hpp).

void MassSpringNetwork::project(double, VecRef y) const { distance_constraints_.project(y); }

double MassSpringNetwork::constraint_residual(CVecRef y) const {
  return distance_constraints_.residual(y);
}

// ---------------------------------------------------------------------------------------------
// Stiffness (models/mass_spring/stiffness_spectrum.hpp).

double MassSpringNetwork::omega_max_bound(CVecRef x) const {
  ensure_adjacency();
  return StiffnessSpectrum(dim_, points_, adjacency_).omega_max_bound(x);
}

std::pair<double, double> MassSpringNetwork::stiffness_eigen_range(CVecRef x) const {
  ensure_adjacency();
  return StiffnessSpectrum(dim_, points_, adjacency_).eigen_range(x);
}

double MassSpringNetwork::omega_max_estimate(CVecRef x) const {
  ensure_adjacency();
  return StiffnessSpectrum(dim_, points_, adjacency_).omega_max_estimate(x);
}

std::optional<double> MassSpringNetwork::stiffness(double, CVecRef y) const {
  if (has_constraints()) return std::nullopt;
  return omega_max_estimate(y.head(dofs()));
}

}  // namespace stiffbench
