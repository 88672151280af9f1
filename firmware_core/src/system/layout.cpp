// The layout's structure: an elimination order of the rows (reverse Cuthill-McKee or minimum
// degree over the rows that share a body, whichever leaves the factor fewer entries; a
// generated kernel's own order for its block) and the entries of J W J^T that can be
// non-zero. Dimension-free: it reads which bodies each row touches, never what the rows are.
#include "planar/kernel.hpp"

namespace legsim {

namespace {
legsim_status layout_pairs(Layout &out, int p0, const uint8_t *first);

// The group of each row once body `sep` is taken out (rows that share another body, directly
// or through other rows, are in one group; numbered in the order of their lowest row), and
// the number of groups; or -1 where a row has no body but sep (it would have no pivot
// without it) or sep twice.
int separated_groups(const Layout &out, int m, int sep, int *group) {
  int parent[kMaxRows], body_row[kMaxBodies];
  for (int b = 0; b < kMaxBodies; ++b) body_row[b] = -1;
  auto root = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (int i = 0; i < m; ++i) {
    parent[i] = i;
    int others = 0;
    for (int s = 0; s < 2; ++s) {
      const int b = out.body[i][s];
      if (b < 0 || b == sep) continue;
      ++others;
      if (body_row[b] < 0) {
        body_row[b] = i;
      } else {
        const int a = root(body_row[b]), c = root(i);
        if (a != c) parent[a < c ? c : a] = a < c ? a : c;  // the lower row is the root
      }
    }
    if (others == 0) return -1;
  }
  int n = 0, number[kMaxRows];
  for (int i = 0; i < m; ++i) {
    const int r = root(i);
    group[i] = r == i ? (number[i] = n++) : number[r];
  }
  return n;
}

// The body, if any, whose removal leaves the most groups, at least three, and that more than
// kSeparatorMinRows rows act on (ties to the lowest body). Those rows are a clique of J W J^T
// in any order, and the Schur complement costs three solves with B a factorization instead:
// with the twelve hip rows of two legs the clique is the cheaper (measured: the general path
// 3 % more a step with the box as the separator, firmware_core/benchmarks/results.md), so
// the two-leg robot, and the leg (six rows on its upper rod), keep the order their generated
// kernels share with this path (kernel_codegen.py's separator: the same rule).
constexpr int kSeparatorMinRows = 12;
int separator_body(const Layout &out, int m, int *group) {
  if (kSeparatorRows < kMaxRows) return -1;  // a build for fewer legs keeps no room for it
  bool seen[kMaxBodies] = {};
  int best = -1, best_groups = 2, g[kMaxRows];
  for (int i = 0; i < m; ++i)
    for (int s = 0; s < 2; ++s) {
      const int b = out.body[i][s];
      if (b < 0 || seen[b]) continue;
      seen[b] = true;
      int on_b = 0;
      for (int r = 0; r < m; ++r) on_b += out.body[r][0] == b || out.body[r][1] == b;
      if (on_b <= kSeparatorMinRows) continue;
      const int n = separated_groups(out, m, b, g);
      if (n > best_groups || (n == best_groups && best >= 0 && b < best)) {
        best = b, best_groups = n;
        for (int r = 0; r < m; ++r) group[r] = g[r];
      }
    }
  return best;
}
}  // namespace

// The coordinate drivers' bodies are known once their values are: finish the
// layout and list the entries of J W J^T that can be non-zero.
namespace {
// Row i of the joint block (rows 0 .. mj-1) is a row of a pinned body's pin: a joint to the
// frame (no second body) on a body that has no other.
bool pin_row(const Layout &out, int mj, int i) {
  if (out.body[i][1] >= 0) return false;
  int rows = 0;  // the body's rows to the frame: 2 for one revolute joint
  for (int j = 0; j < mj; ++j) rows += out.body[j][1] < 0 && out.body[j][0] == out.body[i][0];
  return rows == 2;
}
}  // namespace

namespace {
// A set of rows, one bit each.
constexpr int kRowWords = (kMaxRows + 31) / 32;
struct Rowset {
  uint32_t w[kRowWords];
};
void rowset_clear(Rowset &s) {
  for (uint32_t &x : s.w) x = 0;
}
void rowset_add(Rowset &s, int i) { s.w[i / 32] |= uint32_t(1) << (i % 32); }
void rowset_remove(Rowset &s, int i) { s.w[i / 32] &= ~(uint32_t(1) << (i % 32)); }
bool rowset_has(const Rowset &s, int i) { return (s.w[i / 32] >> (i % 32)) & 1u; }
// |a & b|, and whether a & b has a member below n
int rowset_common(const Rowset &a, const Rowset &b) {
  int n = 0;
  for (int k = 0; k < kRowWords; ++k) n += __builtin_popcount(a.w[k] & b.w[k]);
  return n;
}
bool rowset_common_below(const Rowset &a, const Rowset &b, int n) {
  for (int k = 0; k * 32 < n; ++k) {
    uint32_t x = a.w[k] & b.w[k];
    if (n - k * 32 < 32) x &= (uint32_t(1) << (n - k * 32)) - 1;
    if (x) return true;
  }
  return false;
}

// Rows 0 .. n-1 in reverse Cuthill-McKee order (breadth-first from a least-coupled row,
// neighbours by degree, ties to the lowest index; then reversed): order[p] is the row
// eliminated p-th.
template <typename Share>
void cuthill_mckee(const Share &share, int n, int *order) {
  int degree[kMaxRows], cm[kMaxRows], k = 0;
  bool placed[kMaxRows];
  for (int i = 0; i < n; ++i) {
    degree[i] = 0, placed[i] = false;
    for (int j = 0; j < n; ++j) degree[i] += (j != i && share(i, j));
  }
  while (k < n) {
    int start = -1;
    for (int i = 0; i < n; ++i)
      if (!placed[i] && (start < 0 || degree[i] < degree[start])) start = i;
    placed[start] = true;
    cm[k++] = start;
    for (int head = k - 1; head < k; ++head) {
      for (;;) {  // the unplaced neighbours of cm[head], lowest degree first
        int next = -1;
        for (int j = 0; j < n; ++j)
          if (!placed[j] && share(cm[head], j) && (next < 0 || degree[j] < degree[next])) next = j;
        if (next < 0) break;
        placed[next] = true;
        cm[k++] = next;
      }
    }
  }
  for (int p = 0; p < n; ++p) order[p] = cm[n - 1 - p];
}

// Rows 0 .. n-1 by minimum degree: at each step the row with the fewest neighbours left in
// the elimination graph (ties to the lowest index), whose neighbours then become each
// other's (the fill its elimination makes).
void min_degree(const Rowset *share, int n, int *order) {
  Rowset adj[kMaxRows], alive;
  rowset_clear(alive);
  for (int i = 0; i < n; ++i) adj[i] = share[i], rowset_add(alive, i);
  for (int p = 0; p < n; ++p) {
    int best = -1, best_degree = 0;
    for (int i = 0; i < n; ++i) {
      if (!rowset_has(alive, i)) continue;
      const int d = rowset_common(adj[i], alive);
      if (best < 0 || d < best_degree) best = i, best_degree = d;
    }
    order[p] = best;
    rowset_remove(alive, best);
    Rowset near;
    for (int k = 0; k < kRowWords; ++k) near.w[k] = adj[best].w[k] & alive.w[k];
    for (int j = 0; j < n; ++j)
      if (rowset_has(near, j)) {
        for (int k = 0; k < kRowWords; ++k) adj[j].w[k] |= near.w[k];
        rowset_remove(adj[j], j);
      }
  }
}

// L's entries below the diagonal (fill included) with the rows eliminated in this order
// (symbolic factorization, by position).
int fill(const Rowset *share, const int *order, int n) {
  Rowset l[kMaxRows];
  int count = 0;
  for (int p = 0; p < n; ++p) {
    rowset_clear(l[p]);
    for (int q = 0; q < p; ++q)
      if (rowset_has(share[order[p]], order[q])) rowset_add(l[p], q);
    // L_pq is non-zero where A_pq is, or L_pk and L_qk both are for some k < q
    for (int q = 0; q < p; ++q)
      if (!rowset_has(l[p], q) && rowset_common_below(l[p], l[q], q)) rowset_add(l[p], q);
    count += rowset_common(l[p], l[p]);
  }
  return count;
}

// The rows of a body's pin (its one revolute joint to the frame) moved to just before the
// first other row on that body: they couple only rows on their body, which share it
// anyway (no fill), and every pivot after them is then the one of the system with the
// pinned bodies on their angles alone, which the kernels solve for RK4's stages
// (kernel_codegen.py's Reduced, pins_first): the same pivots to round-off, so the same
// pivot floor decides alike there.
inline void pins_first(const Layout &out, const bool *is_pin, int *order, int n) {
  int result[kMaxRows], k = 0;
  bool placed[kMaxRows];
  for (int i = 0; i < n; ++i) placed[i] = false;
  for (int p = 0; p < n; ++p) {
    const int i = order[p];
    if (is_pin[i]) continue;
    for (int s = 0; s < 2; ++s)
      for (int l = 0; l < n; ++l) {
        const int j = order[l];
        if (is_pin[j] && !placed[j] && out.body[i][s] >= 0 && out.body[j][0] == out.body[i][s])
          result[k++] = j, placed[j] = true;
      }
    result[k++] = i;
  }
  for (int l = 0; l < n; ++l)
    if (is_pin[order[l]] && !placed[order[l]]) result[k++] = order[l];
  for (int p = 0; p < n; ++p) order[p] = result[p];
}
}  // namespace

void layout_path(Layout &out) {
  const Kernel *k = out.kernel;
  // the kernel's block is the whole system: no rows after it (a sliding contact's normal
  // row, a stop, a driver would follow the block)
  const bool whole = k && out.m == k->mj;
  out.path.dynamics = whole && k->dynamics ? k : nullptr;
#if LEGSIM_KERNELS_NEWTON_FUSED
  out.path.newton = whole && (k->newton || k->newton_fused) ? k : nullptr;
#else
  out.path.newton = whole && k->newton ? k : nullptr;
#endif
  out.path.factored = whole && k->factored ? k : nullptr;
#if LEGSIM_KERNELS_REDUCED
  out.path.reduced = whole && k->accelerations && k->end ? k : nullptr;
#if LEGSIM_MAX_CONTACTS >= 2
  out.path.stage = out.path.reduced;
  // after the joint kernel's block, every contact's rows in contact order, one contact's
  // normal row alone (sliding: Data::dyn's rows follow the contacts' states) and the others'
  // both (stuck): the stages of that stance with the sliding foot
  if (!out.path.stage && k && k->nc == 0) {
    int slide = -1, c = 0, i = k->mj;
    bool ok = true;
    while (ok && i < out.m) {
      ok = out.src[i].kind == RowKind::ContactNormal && out.src[i].index == c;
      if (ok && i + 1 < out.m && out.src[i + 1].kind == RowKind::ContactTangent && out.src[i + 1].index == c) {
        i += 2;
      } else {
        ok = ok && slide < 0;
        slide = c;
        ++i;
      }
      ++c;
    }
    const Kernel *s = ok && slide >= 0 ? kernel_find_slide(k, slide) : nullptr;
    for (int r = k->mj; s && ok && r < out.m; ++r)  // on the stance's feet
      ok = s->nc == c && out.body[r][0] == s->contact_body[out.src[r].index];
    if (s && ok && c == s->nc && s->mj == out.m) out.path.stage = s;
  }
#endif
#else
  out.path.reduced = nullptr;  // a build without them leaves their callers out too
#if LEGSIM_MAX_CONTACTS >= 2
  out.path.stage = nullptr;
#endif
#endif
}

legsim_status layout_finish(Layout &out, const DriverValues &dv) {
  const int m = out.m;
  for (int i = 0; i < m; ++i)
    if (out.src[i].kind == RowKind::Coordinate) out.body[i][0] = int8_t(dv.coord[out.src[i].index].body);
  out.separator = -1;
  int sep = -1;
  auto share_body = [&](int i, int j) {
    for (int si = 0; si < 2; ++si)
      for (int sj = 0; sj < 2; ++sj)
        if (out.body[i][si] >= 0 && out.body[i][si] != sep && out.body[i][si] == out.body[j][sj]) return true;
    return false;
  };
  const Kernel *k = out.kernel;
  if (k) {
    // the joint block in the kernel's order, the other rows after it as they come: their
    // rows of the factor are the Schur complement's on the kernel's factor
    for (int i = 0; i < m; ++i) out.perm[i] = i < k->mj ? RowIndex(k->perm[i]) : RowIndex(i);
    return layout_pairs(out, k->mj, k->first);
  }
  // The block (the joint rows, or a stance's joint and contact rows: Layout::block) in an
  // elimination order, the other rows after it as they come. tools/kernel_codegen.py
  // orders a kernel's block by the same rule (block_order), so the two paths factor alike.
  int mj = 0;
  while (mj < m && out.src[mj].kind == RowKind::Joint) ++mj;
  const int nb = LEGSIM_MAX_CONTACTS > 0 && out.block > mj ? int(out.block) : mj;
  // Every row in the block and a body shared by three or more groups of them: the rows
  // are ordered (and the envelope built) on B, the system less that body's share, whose
  // groups share nothing, each group's rows together; the solves add the body back
  // (linear_solve.cpp).
  int group[kMaxRows];
  if (nb == m && m > 0) sep = separator_body(out, m, group);
  // reverse Cuthill-McKee over the joint rows (which keeps the envelope small), the
  // contact rows after them
  int rcm[kMaxRows];
  cuthill_mckee(share_body, mj, rcm);
  for (int i = mj; i < nb; ++i) rcm[i] = i;
  bool is_pin[kMaxRows];
  for (int i = 0; i < nb; ++i) is_pin[i] = i < mj && pin_row(out, mj, i);
  pins_first(out, is_pin, rcm, nb);
  // or, for a stance, minimum degree over the whole block where that leaves fewer entries
  // in the factor (a robot: each leg's rows first, the rows on the box, which all share it,
  // last). A joint block keeps reverse Cuthill-McKee: the rows after it solve against it
  // through its envelope, which a minimum-degree order spreads. (A build without contacts
  // has no stance: its image leaves this out.)
  if (LEGSIM_MAX_CONTACTS > 0 && nb > mj) {
    Rowset share[kMaxRows];
    for (int i = 0; i < nb; ++i) {
      rowset_clear(share[i]);
      for (int j = 0; j < nb; ++j)
        if (j != i && share_body(i, j)) rowset_add(share[i], j);
    }
    int md[kMaxRows];
    min_degree(share, nb, md);
    pins_first(out, is_pin, md, nb);
    if (fill(share, md, nb) < fill(share, rcm, nb))
      for (int p = 0; p < nb; ++p) rcm[p] = md[p];
  }
  if (sep >= 0) {
    // each group's rows together, in the order above (B is block diagonal by group: the
    // same fill, and no envelope across groups)
    int by_group[kMaxRows], k2 = 0;
    for (int g = 0; k2 < nb; ++g)
      for (int p = 0; p < nb; ++p)
        if (group[rcm[p]] == g) by_group[k2++] = rcm[p];
    for (int p = 0; p < nb; ++p) rcm[p] = by_group[p];
    out.separator = int8_t(sep);
  }
  for (int p = 0; p < nb; ++p) out.perm[rcm[p]] = RowIndex(p);
  for (int i = nb; i < m; ++i) out.perm[i] = RowIndex(i);
  return layout_pairs(out, 0, nullptr);
}

namespace {
// The entries of J W J^T at positions from p0 on (those before: the kernel's block, whose
// envelope is first[]) and each position's envelope.
legsim_status layout_pairs(Layout &out, int p0, const uint8_t *first) {
  const int m = out.m;
  int np = 0;
  for (int p = 0; p < m; ++p) out.first[p] = p < p0 ? RowIndex(first[p]) : RowIndex(p);
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j)
      for (int si = 0; si < 2; ++si)
        for (int sj = 0; sj < 2; ++sj) {
          const int pi = out.perm[i], pj = out.perm[j];
          if (pj > pi || (i == j && sj < si)) continue;  // each lower entry (and diagonal pair) once
          if (pi < p0) continue;                          // the kernel's own
          if (out.body[i][si] < 0 || out.body[i][si] != out.body[j][sj]) continue;
          if (out.body[i][si] == out.separator) continue;  // B's entries only
          if (np >= kMaxPairs) return LEGSIM_ERR_CAPACITY;
          out.pair[np++] = {uint16_t(kBodyDof * (2 * i + si)), uint16_t(kBodyDof * (2 * j + sj)), 0};
          if (pj < out.first[pi]) out.first[pi] = RowIndex(pj);
        }
  out.npairs = np;
  return layout_storage(out, p0, kFactorEntries);
}
}  // namespace

legsim_status layout_storage(Layout &out, int p0, int capacity) {
  const int m = out.m;
  uint16_t row[kMaxRows];
  int n = 0;
  for (int p = 0; p < m; ++p) {
    // a row after the kernel's block that reaches into it: from column 0 (Layout::row)
    const int lo = p >= p0 && out.first[p] < p0 ? 0 : out.first[p];
    row[p] = uint16_t(n - lo);  // n >= p >= lo: each position before holds its diagonal
    n += p - lo + 1;
    if (n > capacity) return LEGSIM_ERR_CAPACITY;
  }
  // factor_build's dense fallback with a separator: the whole lower triangle
  if (out.separator >= 0 && m * (m + 1) / 2 > n) n = m * (m + 1) / 2;
  if (n > capacity) return LEGSIM_ERR_CAPACITY;
  for (int p = 0; p < m; ++p) out.row[p] = row[p];
  out.entries = n;
  constexpr int kRowCoef = 2 * kBodyDof;  // Pair::ci, cj: kBodyDof * (2 * row + slot)
  for (int k = 0; k < out.npairs; ++k) {
    Pair &pr = out.pair[k];
    const int pi = out.perm[pr.ci / kRowCoef], pj = out.perm[pr.cj / kRowCoef];
    pr.aij = uint16_t(out.row[pi] + pj);
  }
  return LEGSIM_OK;
}

}  // namespace legsim
