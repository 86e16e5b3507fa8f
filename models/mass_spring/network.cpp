#include "models/mass_spring/network.hpp"

#include "models/detail/with_dim.hpp"
#include "models/mass_spring/network_parts.hpp"

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

using detail::face_drag;
using detail::for_points;

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

namespace {

// part[p]: the partition q of point p, the first q with np·(q+1)/parts > p (inverting
// p0 = np·q/parts).
std::vector<std::int32_t> point_partitions(Index np, Index parts) {
  const auto owner = [&](Index p) {
    Index q = (p * parts) / np;
    while (q + 1 < parts && np * (q + 1) / parts <= p) ++q;
    while (q > 0 && np * q / parts > p) --q;
    return q;
  };
  std::vector<std::int32_t> part(static_cast<std::size_t>(np));
  for (Index p = 0; p < np; ++p)
    part[static_cast<std::size_t>(p)] = static_cast<std::int32_t>(owner(p));
  return part;
}

// The distinct (k, L) pairs (by bits), appended to k and rest as they are first met; (k, L)
// returns the pair's index: a short linear search while there are few, then a hash.
class SpringKinds {
 public:
  SpringKinds(std::vector<double>& k, std::vector<double>& rest) : k_(k), rest_(rest) {}

  std::int32_t operator()(double k, double rest) {
    const std::pair<std::uint64_t, std::uint64_t> key{std::bit_cast<std::uint64_t>(k),
                                                      std::bit_cast<std::uint64_t>(rest)};
    if (kinds_.empty()) {
      for (std::size_t t = 0; t < k_.size(); ++t)
        if (std::bit_cast<std::uint64_t>(k_[t]) == key.first &&
            std::bit_cast<std::uint64_t>(rest_[t]) == key.second)
          return static_cast<std::int32_t>(t);
      if (k_.size() == 16)  // from now on, a hash table
        for (std::size_t t = 0; t < k_.size(); ++t)
          kinds_.emplace(std::pair{std::bit_cast<std::uint64_t>(k_[t]),
                                   std::bit_cast<std::uint64_t>(rest_[t])},
                         static_cast<std::int32_t>(t));
    } else if (const auto it = kinds_.find(key); it != kinds_.end()) {
      return it->second;
    }
    const auto t = static_cast<std::int32_t>(k_.size());
    k_.push_back(k);
    rest_.push_back(rest);
    if (!kinds_.empty()) kinds_.emplace(key, t);
    return t;
  }

 private:
  struct KeyHash {
    std::size_t operator()(const std::pair<std::uint64_t, std::uint64_t>& key) const {
      return std::hash<std::uint64_t>()(key.first * 0x9E3779B97F4A7C15ULL ^ key.second);
    }
  };
  std::vector<double>& k_;
  std::vector<double>& rest_;
  std::unordered_map<std::pair<std::uint64_t, std::uint64_t>, std::int32_t, KeyHash> kinds_;
};

// The springs m of a group listed by key(e) = (j - i, (k, L) pair, part, i) without its i, then
// by i, which puts each run's springs together (a stable sort by (key, i)): one bucket per key,
// in key order, each in the network's order and sorted by i only when it is not already (a
// lattice lists its springs by first end).
template <class Key>
std::vector<std::int32_t> run_order(const std::vector<std::int32_t>& m,
                                    const std::vector<Spring>& springs, const Key& key) {
  std::map<std::tuple<Index, std::int32_t, std::uint8_t>, std::vector<std::int32_t>> buckets;
  for (const std::int32_t e : m) {
    const auto [off, kd, imp, i0] = key(e);
    buckets[{off, kd, imp}].push_back(e);
  }
  std::vector<std::int32_t> sorted;
  sorted.reserve(m.size());
  for (auto& [bucket_key, members_of_key] : buckets) {
    const auto first_end = [&](std::int32_t a, std::int32_t b) {
      return springs[static_cast<std::size_t>(a)].i < springs[static_cast<std::size_t>(b)].i;
    };
    if (!std::is_sorted(members_of_key.begin(), members_of_key.end(), first_end))
      std::stable_sort(members_of_key.begin(), members_of_key.end(), first_end);
    sorted.insert(sorted.end(), members_of_key.begin(), members_of_key.end());
  }
  return sorted;
}

// Per partition q of the np points, [a, b) at 2q, 2q + 1: its longest run of points p with
// touched_by[p] < 0 (no spring between partitions touches them).
std::vector<Index> untouched_ranges(const std::vector<Index>& touched_by, Index np, Index parts) {
  std::vector<Index> ranges(2 * static_cast<std::size_t>(parts), 0);
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
    ranges[2 * static_cast<std::size_t>(q)] = best_a;
    ranges[2 * static_cast<std::size_t>(q) + 1] = best_b;
  }
  return ranges;
}

}  // namespace

// Springs of the right-hand side in structure-of-arrays order, grouped by partition of the
// points (see the header comment and RhsSprings); within each group, the runs first, then the
// loose springs in the network's order.
void MassSpringNetwork::pack_rhs_springs() {
  const Index np = num_points();
  // The partition count depends on the size only (not on the threads or on the parallel
  // threshold), so the serial and the parallel path sum in the same order.
  const Index parts = np >= 64 * kRhsPartitions ? kRhsPartitions : 1;
  const std::vector<std::int32_t> part = point_partitions(np, parts);
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

  RhsSprings& rs = rhs_springs_;
  const std::size_t ns = springs_.size();
  require_input(dofs() <= std::numeric_limits<std::int32_t>::max(),
                name_ + ": more than 2^31 - 1 coordinates (the springs store 32-bit offsets)");
  SpringKinds kind_of(rs.k, rs.rest);
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
    // Runs: springs of one (j - i, (k, L) pair, part) whose first ends are consecutive points,
    // together in `sorted` (run_order). Runs shorter than kMinRun stay loose.
    const auto key = [&](std::int32_t e) {
      const Spring& sp = springs_[static_cast<std::size_t>(e)];
      return std::tuple{sp.j - sp.i, kind[static_cast<std::size_t>(e)],
                        implicit[static_cast<std::size_t>(e)], sp.i};
    };
    const std::vector<std::int32_t> sorted = run_order(m, springs_, key);
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
  late_clear_ = untouched_ranges(touched_by, np, parts);
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

using detail::kernel_isa_in_use;
using detail::spring_group;
using detail::SpringArgs;

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
