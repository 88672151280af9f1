#!/usr/bin/env python3
"""Generate the fixed-sparsity joint-block kernels of the compiled-in models (kernel.hpp).

    kernel_codegen.py --out legsim_kernels.cpp leg.json robot.json

For each distinct structure among the files' variants (joint kinds and the bodies they
join; with --no-stance left out, also each model with contacts' stance: its joint rows and
both rows of every contact, all stuck), writes straight-line C++ for those rows:
  rows       Phi, the Jacobian, nu and gamma: calls of the row units (planar/rows.hpp,
             which the general path calls too) with the joints' and bodies' indices fixed,
             one sin/cos pair per body, no dispatch; the physics is in those units alone,
             this file knows each kind's sparsity (joint_rows);
  factor     the lower envelope of J W J^T (products with the Jacobian's constant
             entries folded away) and its factor L D L^T in the general path's order
             (reverse Cuthill-McKee, the contact rows after) with its fill worked out here
             (symbolic factorization), stored as the general code stores it (1 / D on the
             diagonal);
  solve      L D L^T x = b with the row permutation folded in;
  forward, backward, j_times, jt_times over the non-zeros only (the rows after the block);
  dynamics   the whole forward-dynamics solve fused, its values in locals,
  newton     one generalized-alpha Newton iteration fused, and
  factored   the forward-dynamics solve with the factor given, the joints' reactions with
             it: for each model's main system only (its joints, or its stance), of at most
             --fused-max-rows rows;
  and, where bodies are pinned to the frame (not with --no-reduced), RK4's solves in the
  reduced system where those bodies keep their angles alone (Reduced), applying the
  actuators' forces from their own sin/cos:
  accelerations   a stage's accelerations (on a stance also with each stuck foot as a pin
                  to the ground: its two contact rows drop out, rows_pin in kernel.hpp);
  end             the step's end (and a restart): the projection test's residual and
                  drift, then the accelerations, every row's multiplier, the reactions and
                  the condition estimate.
Every piece but the reduced ones does the general path's arithmetic in the same order, so
both give the same numbers bit for bit; the reduced ones agree to round-off
(tests/core/test_kernels.c).
The geometry (joint points) is read from the Model at run time: the kernel depends on the
structure only (the joints, the contacts' bodies and the actuators' joints), and
kernel_find (in the generated file) picks it by that structure.
Each kernel is compiled only where the build's capacities hold its model. Python 3.11+,
standard library only; the models' structure comes from the model loader
(legsim_model --emit-structure: one JSON file per model file, named after it).
"""
from __future__ import annotations

import argparse
import json
import os
import sys
from typing import NamedTuple

KIND = {"revolute_to_frame": 0, "revolute": 1, "prismatic": 2, "slot": 3}
NROWS = {"revolute_to_frame": 2, "revolute": 2, "prismatic": 2, "slot": 1}
# each kind's row unit (rows.hpp): <unit>_position (Phi, the Jacobian), <unit>_gamma
UNIT = {"revolute_to_frame": "revolute", "revolute": "revolute", "prismatic": "prismatic", "slot": "slot"}
# what each kind's <unit>_gamma reads of the JointRows its <unit>_position filled
GAMMA_READS = {"revolute_to_frame": ("sa",), "revolute": ("sa", "sb"), "prismatic": ("d",), "slot": ("sa", "d")}
V = None  # a Jacobian entry known only at run time (rows.coef)


def joint_rows(joints):
    """Per joint row: its two bodies (-1: none) and per slot the 3 coefficients,
    each a constant or V (as the row units of rows.hpp write them): a kind's sparsity."""
    rows = []
    for j in joints:
        a, b = j["body"]
        kind = j["kind"]
        if kind in ("revolute_to_frame", "revolute"):
            other = b if kind == "revolute" else -1
            rows.append(((a, other), ((1, 0, V), (-1, 0, V))))
            rows.append(((a, other), ((0, 1, V), (0, -1, V))))
        elif kind == "prismatic":
            rows.append(((a, b), ((0, 0, -1), (0, 0, 1))))
            rows.append(((a, b), ((V, V, V), (V, V, 0))))
        else:  # slot
            rows.append(((a, b), ((V, V, V), (V, V, V))))
    return rows


def rcm_order(m, share):
    """Rows in elimination order: reverse Cuthill-McKee exactly as layout_finish
    (constraints.cpp) orders the joint block, ties to the lowest index, so that the
    kernel and the general path factor the same matrix in the same order."""
    deg = [sum(1 for j in range(m) if j != i and share[i][j]) for i in range(m)]
    placed, order = [False] * m, []
    while len(order) < m:
        start = min((i for i in range(m) if not placed[i]), key=lambda i: (deg[i], i))
        placed[start] = True
        order.append(start)
        head = len(order) - 1
        while head < len(order):  # breadth first, the unplaced neighbours lowest degree first
            while True:
                near = [j for j in range(m) if not placed[j] and share[order[head]][j]]
                if not near:
                    break
                nxt = min(near, key=lambda j: (deg[j], j))
                placed[nxt] = True
                order.append(nxt)
            head += 1
    return order[::-1]


def min_degree_order(m, share):
    """Rows in elimination order by minimum degree, exactly as layout_finish
    (constraints.cpp) orders a block: at each step the row with the fewest neighbours
    left in the elimination graph (ties to the lowest index), whose neighbours then
    become neighbours of each other (the fill its elimination makes). On a robot the rows
    of each leg go first and the rows on the box, which all share it, last."""
    adj = [{j for j in range(m) if j != i and share[i][j]} for i in range(m)]
    alive, order = set(range(m)), []
    while alive:
        i = min(alive, key=lambda r: (len(adj[r] & alive), r))
        near = adj[i] & alive
        for j in near:
            adj[j] |= near - {j}
        alive.remove(i)
        order.append(i)
    return order


def fill(order, share):
    """The number of L's entries below the diagonal (fill included) when the rows are
    eliminated in this order (symbolic factorization)."""
    n, reach = 0, []
    for p, i in enumerate(order):
        # row p's pattern: A's entries, and every column q that a column before it in the
        # row reaches (L_pq non-zero when L_pk and L_qk both are, k < q)
        lp = {q for q in range(p) if share[i][order[q]]}
        for q in range(p):
            if q not in lp and any(k in reach[q] for k in lp if k < q):
                lp.add(q)
        reach.append(lp)
        n += len(lp)
    return n


def block_order(mj, m, share, rows, pinned):
    """The elimination order of a kernel's block of m rows (its joint rows 0 .. mj-1, then
    the stance's contact rows), the general path's rule (layout_finish): reverse
    Cuthill-McKee over the joint rows with the contact rows after them, or, for a stance,
    minimum degree over all the block's rows where that leaves fewer entries in the factor;
    the pin rows moved ahead of the rows on their body either way (pins_first). A joint
    block keeps reverse Cuthill-McKee: the rows after it (a sliding foot's, a stop's) solve
    against it through its envelope, which a minimum-degree order spreads (a robot with a
    foot sliding took 10 % more per step)."""
    rcm = pins_first(rcm_order(mj, share) + list(range(mj, m)), rows, pinned, mj)
    if m == mj:
        return rcm
    md = pins_first(min_degree_order(m, share), rows, pinned, mj)
    return md if fill(md, share) < fill(rcm, share) else rcm


SEPARATOR_MIN_ROWS = 12  # layout.cpp's kSeparatorMinRows


def separator(rows):
    """The body whose removal splits the rows into the most groups sharing no other body, at
    least three, and that more than SEPARATOR_MIN_ROWS rows act on (ties to the lowest
    body), or None: layout_finish's separator_body. The
    general path factors such a block with the body as a Schur complement (a robot's box on
    three or more legs: linear in the legs); the generator has no such kernel, so it leaves
    the block to the general path rather than factor it in another order."""
    best, best_groups = None, 2
    for b in sorted({x for r in rows for x in r[0] if x >= 0}):
        if any(all(x < 0 or x == b for x in r[0]) or list(r[0]).count(b) > 1 for r in rows):
            continue  # a row on b alone (or twice) has no pivot in B
        if sum(b in r[0] for r in rows) <= SEPARATOR_MIN_ROWS:
            continue  # the clique of its rows costs less than the Schur complement
        parent = list(range(len(rows)))

        def root(i):
            while parent[i] != i:
                i = parent[i]
            return i
        first = {}
        for i, r in enumerate(rows):
            for x in r[0]:
                if x < 0 or x == b:
                    continue
                if x in first:
                    a, c = root(first[x]), root(i)
                    parent[max(a, c)] = min(a, c)
                else:
                    first[x] = i
        groups = len({root(i) for i in range(len(rows))})
        if groups > best_groups:
            best, best_groups = b, groups
    return best


def pinned_bodies(joints):
    """Bodies pinned to the frame by one revolute joint (and no other joint to the frame)."""
    to_frame = [j["body"][0] for j in joints if j["kind"] == "revolute_to_frame"]
    return {b for b in to_frame if to_frame.count(b) == 1}


def pins_first(order, rows, pinned, mj=None):
    """order with the rows of each pinned body's pin (its rows to the frame: no second body;
    joint rows only, the first mj when given) moved to just before the first other row on
    that body (layout_finish, constraints.cpp, does the same): every row's pivot after them
    is then the reduced system's (Reduced)."""
    mj = len(rows) if mj is None else mj
    pin = [i < mj and r[0][1] < 0 and r[0][0] in pinned for i, r in enumerate(rows)]
    out = []
    for i in order:
        if pin[i]:
            continue
        for b in rows[i][0]:
            out += [k for k in order if pin[k] and rows[k][0][0] == b and k not in out]
        out.append(i)
    return out + [k for k in order if pin[k] and k not in out]


class Pin(NamedTuple):
    """A pinned body's pin in the reduced system (Reduced): the C names of its point's offset
    from the body's centre (sx, sy) and of its rows' gamma in the world axes (g0, g1), its
    first row, and its joint (None: a stuck contact's rows)."""
    sx: str
    sy: str
    g0: str
    g1: str
    r: int
    n: int | None


def product(terms):
    """C text of a signed sum of products [(constant, [factors])]; "0" when empty."""
    out = []
    for c, vs in terms:
        if c == 0:
            continue
        parts = ([f"real({abs(c)})"] if abs(c) != 1 else []) + vs
        out.append(("-" if c < 0 else "+", " * ".join(parts) or "1"))
    if not out:
        return "0"
    return ("-" if out[0][0] == "-" else "") + out[0][1] + "".join(f" {sg} {b}" for sg, b in out[1:])


def group(dots):
    """Sum of per-slot dot products, each summed apart first (the general path's rounding)."""
    dots = [d for d in dots if d != "0"]
    if not dots:
        return "0"
    return " + ".join(d if len(dots) == 1 else f"({d})" for d in dots)


class Kernel:
    """The kernel of one structure: its joint rows (a joint kernel), or its joint rows and
    both rows of every contact, all stuck (a stance kernel: the robot standing), or with
    slide that contact's normal row alone (RK4's stages with one foot sliding, emit_slide)."""

    def __init__(self, name, model, stance=False, slide=None):
        self.name = name
        # slide: a stance's contact that slides (its normal row alone, mu_k N along the
        # ground on its normal multiplier: RK4's stages only, Reduced)
        self.slide = slide
        self.nb = len(model["bodies"])
        self.joints = model["joints"]
        self.contacts = model.get("contacts", []) if stance else []
        # each actuator's prismatic joint, cylinder and rod (model.cpp: its joint's bodies)
        self.actuators = [(a["joint"], *self.joints[a["joint"]]["body"]) for a in model.get("actuators", [])]
        self.rows = joint_rows(self.joints)
        mj = len(self.rows)
        self.contact_row = []  # per contact: its first row
        for n, c in enumerate(self.contacts):  # normal then tangential row, on the foot's body alone
            self.contact_row.append(len(self.rows))
            self.rows += [((c["body"], -1), ((V, V, V), (0, 0, 0)))] * (1 if n == slide else 2)
        # the joint rows in reverse Cuthill-McKee order, the contact rows after them as the
        # general path places rows after a joint kernel's block (so both factor alike)
        self.structure(mj)
        self.fused = True  # generate() decides
        self.reduced = True  # and this (RK4's reduced solves)
        self.newton_fused = True  # and whether newton gives the forces and the residual itself

    def structure(self, mj, order=None):
        """The elimination order of the rows (rows mj.. kept last, in order; or the order
        given) and the patterns of J W J^T and of its factor by position."""
        m = self.m = len(self.rows)
        share = [[any(x >= 0 and x == y for x in self.rows[i][0] for y in self.rows[j][0])
                  for j in range(m)] for i in range(m)]
        if order is None:
            order = block_order(mj, m, share, self.rows, pinned_bodies(self.joints))
        self.perm = [0] * m
        for p, i in enumerate(order):
            self.perm[i] = p
        self.row_at = order  # position -> row
        # A's lower pattern and L's (fill included), by position
        self.a_nz = [[share[order[p]][order[q]] for q in range(m)] for p in range(m)]
        lp = [set() for _ in range(m)]
        for p in range(m):
            for q in range(p):
                if self.a_nz[p][q] or any(k in lp[q] for k in lp[p] if k < q):
                    lp[p].add(q)
        self.l_nz = [sorted(s) for s in lp]
        self.first = [min(self.l_nz[p]) if self.l_nz[p] else p for p in range(m)]

    def work(self):
        """The order's cost: over the factor's rows, l (l + 1) / 2 with l the row's entries
        in L. It ranks the straight-line code's instructions better than the count of its
        products (the robot's stage: 808 and 27,257 instructions a step under reverse
        Cuthill-McKee, 984 and 27,398 under minimum degree, which has fewer products)."""
        return sum(len(x) * (len(x) + 1) // 2 for x in self.l_nz)

    def at(self, p, q):
        """Entry (p, q) of the factor's packed storage (Layout::row, layout_storage: the
        envelope row after row, the block's rows first). A reduced system without a pinned
        body reads its whole system's factor (the same order): the whole system's storage."""
        if getattr(self, "full", self) is not self:
            return self.full.at(p, q)
        if not hasattr(self, "_row"):
            self._row, n = [], 0
            for r in range(self.m):
                self._row.append(n - self.first[r])
                n += r - self.first[r] + 1
        return self._row[p] + q

    def coef(self, i, s, k, local=False):
        """(constant, [factor]) of a Jacobian entry: a constant, or the run-time value in
        rows.coef (or in the fused functions' local c<row>_<slot>_<coordinate>)."""
        c = self.rows[i][1][s][k]
        if isinstance(c, str):  # a local of its own (the reduced system's)
            return (1, [c])
        if c is not V:
            return (c, [])
        return (1, [f"c{i}_{s}_{k}" if local else f"c[{i}][{s}][{k}]"])

    def w_name(self, b, k):
        """M^-1's entry of body b's coordinate k."""
        return f"w[{3 * b + k}]"

    def signature(self):
        return (tuple((KIND[j["kind"]], j["body"][0], j["body"][1]) for j in self.joints) + (self.nb,)
                + tuple(c["body"] for c in self.contacts) + (len(self.contacts),)
                + tuple(self.actuators) + (len(self.actuators),))

    # ---- the pieces, as lines of C++ over named values ----
    @staticmethod
    def joint_locals(n, j, r, part=None):
        """One joint's rows as locals (phi<r>, gam<r>, c<r>_<slot>_<k>, the entries
        joint_rows marks V), from its row unit (rows.hpp) called on its bodies' poses pose<b>
        into a JointRows in a block of its own, so that only one joint's JointRows is live at
        a time (out of line, as at -Os on Cortex-M, each would otherwise keep its own stack
        slot for the whole kernel). part "q": the positions' part alone (Phi, the Jacobian),
        keeping in locals what the gamma unit reads back (sa<n>, sb<n>, d<n>); "v": the
        velocities' (gamma) from those; None: both in one block. Also names a prismatic
        joint's d, its rate and d.n (dx<n>, dy<n>, ddx<n>, ddy<n>, dn<n>: an actuator's,
        forces_locals) and a pin's offset (sax<n>, say<n>: the pin units')."""
        kind, (a, b) = j["kind"], j["body"]
        unit = UNIT[kind]
        other = "nullptr" if kind == "revolute_to_frame" else f"&pose{b}" if kind == "revolute" else f"pose{b}"
        joint = "" if kind == "prismatic" else f"model.joint[{n}], "  # its rows have no joint points
        q, v = [], []  # (local, the JointRows field it takes)
        for e, (bodies, slots) in enumerate(joint_rows([j])):
            q.append((f"phi{r + e}", f"phi[{e}]"))
            q += [(f"c{r + e}_{sl}_{k}", f"coef[{e}][{sl}][{k}]") for sl in range(2) for k in range(3)
                  if bodies[sl] >= 0 and slots[sl][k] is V]
            v.append((f"gam{r + e}", f"gamma[{e}]"))
        if kind == "prismatic":
            q += [(f"dx{n}", "d.x"), (f"dy{n}", "d.y"), (f"dn{n}", "phi[1]")]
            v += [(f"ddx{n}", "dd.x"), (f"ddy{n}", "dd.y")]
        if kind == "revolute_to_frame":
            q += [(f"sax{n}", "sa.x"), (f"say{n}", "sa.y")]
        keep = GAMMA_READS[kind] if part is not None else ()  # what gamma reads, across parts
        o = [f"  // joint {n}: {kind}, rows {r}.."]
        if part != "v":
            o.append("  [[maybe_unused]] real " + ", ".join(x for x, _ in q) + ";")
            o += [f"  XY {f}{n};" for f in keep]
        if part != "q":
            o.append("  [[maybe_unused]] real " + ", ".join(x for x, _ in v) + ";")
        o.append("  {")
        o.append("    JointRows J;")
        if part != "v":
            o.append(f"    {unit}_position({joint}pose{a}, {other}, J);")
            o.append("    " + " ".join(f"{x} = J.{f};" for x, f in q))
            o += [f"    {f}{n} = J.{f};" for f in keep]
        else:
            o += [f"    J.{f} = {f}{n};" for f in keep]
        if part != "q":
            o.append(f"    {unit}_gamma(pose{a}, {other}, J);")
            o.append("    " + " ".join(f"{x} = J.{f};" for x, f in v))
        o.append("  }")
        return o

    def rows_locals(self, shared=None, part=None, velocity=None, trig="body_trig"):
        """sin/cos once per body (through the TrigCache), then its pose pose<b> (rows.hpp), then
        every joint's rows as locals. shared: body -> an earlier body whose angle a
        prismatic joint keeps equal to its own (to round-off after a projection, a stage's
        step further): its pair from that body's by the angle-sum formulas with the small
        difference e (truncation below e^4 / 24 < 5e-18 for |e| < 1e-4; the TrigCache past
        that). part: as joint_locals' (the sin/cos and the positions with "q"; the
        velocities, velocity(n) for coordinate n, default qd[n], with "v"; a stuck contact's
        rows likewise, contact_locals). trig: the function that gives a body's pair (sim.hpp: body_trig, or grid_trig
        without its memory)."""
        vel = velocity or (lambda n: f"qd[{n}]")
        o = []
        used = sorted({b for j in self.joints for b in j["body"] if b >= 0})
        for b in used:
            if part != "v":
                o.append(f"  real s{b}, c{b};")
                a = (shared or {}).get(b)
                if a is None:
                    o.append(f"  {trig}(trig, {b}, q[{3 * b + 2}], s{b}, c{b});")
                else:
                    o.append(f"  if (const real e = q[{3 * b + 2}] - q[{3 * a + 2}]; std::abs(e) < real(1e-4)) {{")
                    o.append("    const real e2 = e * e, se = e - e * e2 * real(1.0 / 6), ce = 1 - e2 * real(0.5);")
                    o.append(f"    s{b} = s{a} * ce + c{a} * se;")
                    o.append(f"    c{b} = c{a} * ce - s{a} * se;")
                    o.append("  } else {")
                    o.append(f"    {trig}(trig, {b}, q[{3 * b + 2}], s{b}, c{b});")
                    o.append("  }")
        # The poses after every trig call: a pair whose address the (out-of-line) call took
        # is then read where it is used, not held in a register or spilled across the calls.
        for b in used:
            if part != "v":
                o.append(f"  BodyPose pose{b} = body_pose(q, {b}, s{b}, c{b});")
            if part != "q":
                o.append(f"  body_velocity(pose{b}, {vel(3 * b)}, {vel(3 * b + 1)}, {vel(3 * b + 2)});")
        r = 0
        for n, j in enumerate(self.joints):
            o += self.joint_locals(n, j, r, part)
            r += NROWS[j["kind"]]
        for k, c in enumerate(self.contacts):
            o += self.contact_locals(k, c["body"], r, part, stuck=k != self.slide)
            r += 2 if k != self.slide else 1
        return o

    @staticmethod
    def contact_locals(k, b, r, part=None, stuck=True):
        """A stuck contact's two rows from contact_row (rows.hpp), as the general path sums
        them (rows_eval: onto 0): the gap along the ground's normal, the offset along its
        tangent from the stick point. part: as joint_locals' (the unit called in each part,
        its gamma taken in "v", once the pose has its velocity)."""
        o = [f"  // contact {k}: {'stuck' if stuck else 'sliding'}, rows {r}.."]
        for e, row, target in (("ground_n", r, "real(0)"), ("ground_t", r + 1, f"dv.stick[{k}]"))[:2 if stuck else 1]:
            if part != "v":
                o.append(f"  real phi{row}, " + ", ".join(f"c{row}_0_{x}" for x in range(3)) + ";")
            if part != "q":
                o.append(f"  real gam{row};")
            o.append("  {  // (a block of its own: joint_locals says why)")
            o.append("    ContactRow C;")
            o.append(f"    contact_row(model.contact[{k}].point, model.ground_point, model.{e}, {target}, real(1), pose{b}, C);")
            if part != "v":
                o.append(f"    phi{row} = real(0) + C.phi;")
                o.append("    " + " ".join(f"c{row}_0_{x} = C.coef[{x}];" for x in range(3)))
            if part != "q":
                o.append(f"    gam{row} = real(0) + C.gamma;")
            o.append("  }")
        return o

    def rows_store(self, rows="rows."):
        """The locals into Rows (the constant entries too: the general code reads them)."""
        o = [f"  real(*c)[2][3] = {rows}coef;"]
        for i in range(self.m):
            for s in range(2):
                if self.rows[i][0][s] < 0:
                    continue
                vals = []
                for k in range(3):
                    cc, vs = self.coef(i, s, k, local=True)
                    vals.append(vs[0] if vs else str(cc))
                o.append(f"  c[{i}][{s}][0] = {vals[0]}, c[{i}][{s}][1] = {vals[1]}, c[{i}][{s}][2] = {vals[2]};")
            o.append(f"  {rows}phi[{i}] = phi{i}, {rows}gamma[{i}] = gam{i}, {rows}nu[{i}] = 0;")
        return o

    def a_entry(self, p, q, local):
        """J W J^T's entry at positions (p, q), as linear_solve.cpp sums it, or "0"."""
        i, j = self.row_at[p], self.row_at[q]
        dots = []  # per pair of slots on one body
        for si in range(2):
            for sj in range(2):
                b = self.rows[i][0][si]
                if b < 0 or b != self.rows[j][0][sj] or (i == j and sj < si):
                    continue
                terms = []
                for k in range(3):
                    c1, v1 = self.coef(i, si, k, local)
                    c2, v2 = self.coef(j, sj, k, local)
                    terms.append((c1 * c2, v1 + [self.w_name(b, k)] + v2))
                dots.append(product(terms))
        return group(dots)

    def factor_locals(self, local, fail, range_if=None):
        """J W J^T's envelope as locals A<p>_<q>, the largest diagonal entry into max_diag
        (which comes in holding the rows after the block's), then L D L^T (linear_solve.cpp):
        L's entries below the diagonal into L<p>_<q>, each through T<p>_<q> = L_pq D_q, and
        iD<p> = 1 / D_p; the pivots' range into pmin, pmax (only where the C condition
        range_if holds, when given; none with range_if False); `fail` on a bad diagonal or
        a pivot <= the floor."""
        m = self.m
        o = []
        for p in range(m):
            for q in range(self.first[p], p + 1):
                v = self.a_entry(p, q, local)
                if v != "0" or q in self.l_nz[p]:
                    o.append(f"  const real A{p}_{q} = {v};")
        for p in range(m):
            o.append(f"  max_diag = A{p}_{p} > max_diag ? A{p}_{p} : max_diag;")
        o.append(f"  if (!(max_diag > 0) || !std::isfinite(max_diag)) {fail}")
        o.append("  const real floor = kPivotFloor * max_diag;")
        if range_if is not False:
            o.append("  pmin = max_diag;")
            o.append("  pmax = 0;")
        o.append("  real d;")
        for p in range(m):
            lp = self.l_nz[p]
            for q in lp:
                sub = "".join(f" - T{p}_{k} * L{q}_{k}" for k in lp if k < q and k in self.l_nz[q])
                o.append(f"  const real T{p}_{q} = A{p}_{q}{sub}, L{p}_{q} = T{p}_{q} * iD{q};")
            sub = "".join(f" - T{p}_{k} * L{p}_{k}" for k in lp)
            o.append(f"  d = A{p}_{p}{sub};")
            o.append(f"  if (!(d > floor)) {fail}")
            if range_if is False:
                pass
            elif range_if:
                o.append(f"  if ({range_if}) pmin = d < pmin ? d : pmin, pmax = d > pmax ? d : pmax;")
            else:
                o.append("  pmin = d < pmin ? d : pmin;")
                o.append("  pmax = d > pmax ? d : pmax;")
            o.append(f"  const real iD{p} = 1 / d;")
        return o

    def factor_store(self, a="a"):
        """L's envelope by position into the general storage (zeros where L has none), the
        diagonal holding 1 / D_p (linear_solve.cpp)."""
        o = []
        for p in range(self.m):
            for q in range(self.first[p], p + 1):
                v = f"iD{p}" if q == p else f"L{p}_{q}" if q in self.l_nz[p] else "0"
                o.append(f"  {a}[{self.at(p, q)}] = {v};")
        return o

    def solve_locals(self, src, dst, lval="L", tmp="u", zero=()):
        """L D L^T y = b with b_p = src(row at p), into dst(row at p): factor_solve's
        permutation folded in, the same operations in the same order as its forward solve,
        scaling and backward solve."""
        L = (lambda p, k: f"L{p}_{k}") if lval == "L" else (lambda p, k: f"a[{self.at(p, k)}]")
        iD = (lambda p: f"iD{p}") if lval == "L" else (lambda p: L(p, p))  # a's diagonal: 1 / D_p
        o = []
        u = tmp
        if zero:
            return self.sparse_solve_locals(src, dst, L, iD, u, zero)
        for p in range(self.m):
            sub = "".join(f" - {L(p, k)} * {u}{k}" for k in self.l_nz[p])
            o.append(f"  real {u}{p} = {src(self.row_at[p])}{sub};")
        o += [f"  {u}{p} *= {iD(p)};" for p in range(self.m)]
        for p in reversed(range(self.m)):
            o += [f"  {u}{k} -= {L(p, k)} * {u}{p};" for k in self.l_nz[p]]
        o += [f"  {dst(self.row_at[p])} = {u}{p};" for p in range(self.m)]
        return o

    def sparse_solve_locals(self, src, dst, L, iD, u, zero):
        """solve_locals' with the rows in zero known to be zero on the right: the entries of
        y still zero are left out (0 - x for a first term: x's value to the sign of a zero)."""
        nz, o = set(), []
        for p in range(self.m):
            sub = "".join(f" - {L(p, k)} * {u}{k}" for k in self.l_nz[p] if k in nz)
            if self.row_at[p] in zero and not sub:
                continue
            nz.add(p)
            o.append(f"  real {u}{p} = {'real(0)' if self.row_at[p] in zero else src(self.row_at[p])}{sub};")
        o += [f"  {u}{p} *= {iD(p)};" for p in range(self.m) if p in nz]
        for p in reversed(range(self.m)):
            if p not in nz:
                continue
            for k in self.l_nz[p]:
                if k in nz:
                    o.append(f"  {u}{k} -= {L(p, k)} * {u}{p};")
                else:
                    nz.add(k)
                    o.append(f"  real {u}{k} = real(0) - {L(p, k)} * {u}{p};")
        o += [f"  {dst(self.row_at[p])} = {u + str(p) if p in nz else 'real(0)'};" for p in range(self.m)]
        return o

    def accelerations_locals(self, lval):
        """dynamics_solve's steps after the factor (with the rows' locals): b = J M^-1 Q - gamma,
        lambda from the factor (lval: "L" its locals, "a" the array), qdd = M^-1 (Q - J^T
        lambda), the joints' reactions where asked, and the status (qdd not finite:
        LEGSIM_ERR_DIVERGED)."""
        nq = 3 * self.nb
        o = [f"  const real t{n} = w[{n}] * force[{n}];" for n in range(nq)]
        o += [f"  const real b{i} = {self.j_expr(i, lambda n: f't{n}', True)} - gam{i};" for i in range(self.m)]
        o += self.solve_locals(lambda i: f"b{i}", lambda i: f"const real l{i}", lval=lval)
        o += [f"  lambda[{i}] = l{i};" for i in range(self.m)]
        o.append("  real z = 0;  // x * 0 is NaN for an infinite or NaN x only")
        for n in range(nq):
            o.append(f"  qdd[{n}] = w[{n}] * (force[{n}] - ({self.jt_expr(n, lambda i: f'l{i}', True)}));")
            o.append(f"  z += qdd[{n}] * real(0);")
        o += self.reactions_locals()
        o.append("  return z == z ? LEGSIM_OK : LEGSIM_ERR_DIVERGED;")
        return o

    def reactions_locals(self):
        """Where reaction is not null, each joint's reaction on its first body from the
        multipliers l<row> (reactions_from_multipliers, constant Jacobian entries folded)."""
        o = ["  if (reaction) {"]
        r = 0
        for n, j in enumerate(self.joints):
            nr = NROWS[j["kind"]]
            for k, name in enumerate(("force_n[0]", "force_n[1]", "moment_nm")):
                terms = [(-self.coef(i, 0, k, True)[0], self.coef(i, 0, k, True)[1] + [f"l{i}"])
                         for i in range(r, r + nr)]
                o.append(f"    reaction[{n}].{name} = {product(terms)};")
            r += nr
        o.append("  }")
        return o

    def forces_locals(self, store=True):
        """Q as locals Q<n>: base (gravity and the force elements) and, where actuators, each
        actuator's axial force Fa along its cylinder's axis (applied_forces' arithmetic in its
        order, forces.cpp; actuator_force gives Fa from the command); with store, written to
        data.force_q too (Data's Q of the step's end; every other reader writes it first)."""
        nq = 3 * self.nb
        q = [f"base[{n}]" for n in range(nq)]
        o = []
        for a, (n, cyl, rod) in enumerate(self.actuators):
            o.append(f"  // actuator {a} (joint {n}: cylinder {cyl}, rod {rod})")
            o.append(f"  const real Fa{a} = actuators ? actuator_force(model.act[{a}], data.act[{a}], data, s{cyl}, c{cyl}, "
                     f"dx{n}, dy{n}, ddx{n}, ddy{n}, pose{cyl}.w) : real(0);")
            o.append(f"  const real fs{a} = Fa{a} * s{cyl}, fc{a} = Fa{a} * c{cyl};")
            i, j = 3 * cyl, 3 * rod
            q[i] = f"{q[i]} - fs{a}"
            q[i + 1] = f"{q[i + 1]} + fc{a}"
            q[i + 2] = f"{q[i + 2]} + Fa{a} * dn{n}"
            q[j] = f"{q[j]} + fs{a}"
            q[j + 1] = f"{q[j + 1]} - fc{a}"
        for n in range(nq):
            o.append(f"  const real Q{n} = {q[n]};")
            if store:
                o.append(f"  data.force_q[{n}] = Q{n};")
        return o

    def j_expr(self, i, x, local):
        dots = []
        for s in range(2):
            b = self.rows[i][0][s]
            if b >= 0:
                dots.append(product([(self.coef(i, s, k, local)[0], self.coef(i, s, k, local)[1] + [x(3 * b + k)])
                                     for k in range(3)]))
        return group(dots)

    def jt_expr(self, n, x, local):
        b, k = divmod(n, 3)
        terms = []
        for i in range(self.m):
            for s in range(2):
                if self.rows[i][0][s] == b:
                    cc, vs = self.coef(i, s, k, local)
                    terms.append((cc, vs + [x(i)]))
        return product(terms)

    def emit(self, sym):
        m = self.m
        o = []
        a = lambda p, q: f"a[{self.at(p, q)}]"  # noqa: E731
        # rows: the row units (rows.hpp) called per joint, as the general path calls them (so
        # the same values to the last bit), one sin/cos pair per body
        o.append(f"LEGSIM_KERNEL_TARGETS void {sym}_rows(const Model &model, [[maybe_unused]] const DriverValues &dv, const VecQ &q, "
                 "const VecQ &qd, Rows &rows, TrigCache *trig) {")
        o += self.rows_locals() + self.rows_store()
        o.append("}\n")
        # J W J^T's block assembled and factored (the rows after it come in through max_diag)
        o.append(f"LEGSIM_KERNEL_TARGETS bool {sym}_factor(const Rows &rows, const real *w, real *a, real &max_diag, real &pmin, "
                 "real &pmax) {")
        o.append("  const real(*c)[2][3] = rows.coef;")
        o += self.factor_locals(False, "return false;") + self.factor_store()
        o.append("  return true;")
        o.append("}\n")
        # entered at position `from` (y zero before it: a row after the block, fill from there)
        o.append(f"LEGSIM_KERNEL_TARGETS void {sym}_forward(const real *a, real *y, int from) {{")
        o.append("  switch (from) {")
        for p in range(m):
            sub = "".join(f" - {a(p, k)} * y[{k}]" for k in self.l_nz[p])
            o.append(f"    case {p}: y[{p}] = y[{p}]{sub};" + (" [[fallthrough]];" if p < m - 1 else ""))
        o.append("    default: break;")
        o.append("  }")
        o.append("}\n")
        o.append(f"LEGSIM_KERNEL_TARGETS void {sym}_backward(const real *a, real *y) {{")
        for p in reversed(range(m)):
            o += [f"  y[{k}] -= {a(p, k)} * y[{p}];" for k in self.l_nz[p]]
        o.append("}\n")
        # the whole solve on the block alone, in row order
        o.append(f"LEGSIM_KERNEL_TARGETS void {sym}_solve(const real *a, real *x) {{")
        o += self.solve_locals(lambda i: f"x[{i}]", lambda i: f"x[{i}]", lval="a")
        o.append("}\n")
        # J x and J^T x
        o.append(f"LEGSIM_KERNEL_TARGETS void {sym}_j_times(const Rows &rows, const real *x, real *y) {{")
        o.append("  const real(*c)[2][3] = rows.coef;")
        o += [f"  y[{i}] = {self.j_expr(i, lambda n: f'x[{n}]', False)};" for i in range(m)]
        o.append("}\n")
        o.append(f"LEGSIM_KERNEL_TARGETS void {sym}_jt_times(const Rows &rows, const real *x, real *y) {{")
        o.append("  const real(*c)[2][3] = rows.coef;")
        o += [f"  y[{n}] = {self.jt_expr(n, lambda i: f'x[{i}]', False)};" for n in range(3 * self.nb)]
        o.append("}\n")
        if not self.fused:
            return "\n".join(o) + "\n" + self.emit_tables(sym, "nullptr", "nullptr", "nullptr")
        # the whole forward-dynamics solve of the joint rows alone, fused (dynamics.cpp's
        # steps with the same arithmetic in the same order, its values kept in locals)
        o.append(f"LEGSIM_KERNEL_TARGETS legsim_status {sym}_dynamics(const Model &model, [[maybe_unused]] const DriverValues &dv, "
                 "const VecQ &q, const VecQ &qd, "
                 "const VecQ &force, TrigCache *trig, Rows *keep_rows, real *keep_a, real *condition, "
                 "VecR &lambda, VecQ &qdd, legsim_reaction *reaction) {")
        o.append("  const real *w = model.minv;")
        o += self.rows_locals()
        o.append("  if (keep_rows) {")
        o += ["  " + x for x in self.rows_store("keep_rows->")]
        o.append("  }")
        o.append("  real max_diag = 0, pmin, pmax;")
        o += self.factor_locals(True, "{ if (condition) *condition = real(INFINITY); return LEGSIM_ERR_SINGULAR; }",
                                range_if="condition")
        o.append("  if (keep_a) {")
        o += ["  " + x for x in self.factor_store("keep_a")]
        o.append("  }")
        o.append("  if (condition) *condition = std::sqrt(pmax / pmin);")
        nq = 3 * self.nb
        o += self.accelerations_locals("L")
        o.append("}\n")
        # one Newton iteration of generalized-alpha (integrator_generalized_alpha.cpp's steps,
        # the same arithmetic in the same order): r = J^T lambda + M qdd1 - Q, the correction
        # dlambda of (J M^-1 J^T) dlambda = beta' Phi - J M^-1 r and J^T dlambda; Phi and the
        # factor kept (the residual report, the reactions' solve); only where generalized-alpha
        # is compiled in (LEGSIM_KERNEL_NEWTON)
        o.append("#if LEGSIM_WITH_GENERALIZED_ALPHA")
        if self.newton_fused:  # Kernel::newton_fused: the forces and the residual too
            o.append(f"LEGSIM_KERNEL_TARGETS legsim_status {sym}_newton(const Model &model, [[maybe_unused]] const DriverValues &dv, "
                     "const VecQ &q, const VecQ &qd, "
                     "const VecQ &base, Data &data, bool actuators, TrigCache *trig, const real *qdd1, const VecR &lambda, "
                     "real bprime, Rows &rows, real *a, real &condition, real &residual, real *res, VecR &dlambda, "
                     "real *jt_dlambda) {")
        else:  # Kernel::newton: Q given whole
            o.append(f"LEGSIM_KERNEL_TARGETS legsim_status {sym}_newton(const Model &model, [[maybe_unused]] const DriverValues &dv, "
                     "const VecQ &q, const VecQ &qd, "
                     "const VecQ &force, TrigCache *trig, const real *qdd1, const VecR &lambda, real bprime, "
                     "Rows &rows, real *a, real &condition, real *res, VecR &dlambda, real *jt_dlambda) {")
        o.append("  const real *w = model.minv, *mass = model.mass;")
        o += self.rows_locals()
        o.append("  " + " ".join(f"(void)gam{i};" for i in range(m)) + "  // the position level: no gamma")
        o += [f"  rows.phi[{i}] = phi{i};" for i in range(m)]
        if self.newton_fused:
            # rows_max_residual's value (the same comparisons in row order), the forces
            o.append("  real rmax = 0;")
            o += [f"  if (!(std::abs(phi{i}) <= rmax)) rmax = std::abs(phi{i});" for i in range(m)]
            o.append("  residual = rmax;")
            o += self.forces_locals()
        o.append("  real max_diag = 0, pmin, pmax;")
        fail = "{ condition = real(INFINITY); return LEGSIM_ERR_SINGULAR; }"
        o += self.factor_locals(True, fail)
        o += self.factor_store("a")
        o.append("  condition = std::sqrt(pmax / pmin);")
        for n in range(nq):
            o.append(f"  const real r{n} = ({self.jt_expr(n, lambda i: f'lambda[{i}]', True)}) + "
                     f"(mass[{n}] * qdd1[{n}] - {f'Q{n}' if self.newton_fused else f'force[{n}]'});")
            o.append(f"  res[{n}] = r{n};")
            o.append(f"  const real t{n} = w[{n}] * r{n};")
        o += [f"  const real b{i} = bprime * phi{i} - ({self.j_expr(i, lambda n: f't{n}', True)});" for i in range(m)]
        o += self.solve_locals(lambda i: f"b{i}", lambda i: f"const real l{i}")
        o += [f"  dlambda[{i}] = l{i};" for i in range(m)]
        o += [f"  jt_dlambda[{n}] = {self.jt_expr(n, lambda i: f'l{i}', True)};" for n in range(nq)]
        o.append("  return LEGSIM_OK;")
        o.append("}\n")
        o.append("#endif")
        # the forward-dynamics solve with the factor given (dynamics.cpp's rows_ready path:
        # the same arithmetic in the same order), and the joints' reactions from its locals
        # (reactions.cpp's arithmetic, constant Jacobian entries folded)
        o.append(f"LEGSIM_KERNEL_TARGETS legsim_status {sym}_factored(const Model &model, [[maybe_unused]] const DriverValues &dv, "
                 "const VecQ &q, const VecQ &qd, const VecQ &force, TrigCache *trig, const real *a, VecR &lambda, "
                 "VecQ &qdd, legsim_reaction *reaction) {")
        o.append("  const real *w = model.minv;")
        o += self.rows_locals()
        o.append("  " + " ".join(f"(void)phi{i};" for i in range(m)) + "  // the acceleration level: no Phi")
        o += self.accelerations_locals("a")
        o.append("}\n")
        # RK4's stages: the accelerations alone, in the reduced system (where a body is pinned)
        reduced = Reduced(self) if self.reduced else None
        # (a structure without a pinned body, as the robot's: on all its rows); a stance's
        # stages with its stuck feet as pins besides (the robot's 36 rows become 32, 4
        # coordinates fewer); its end keeps the contact rows: the condition estimate is the
        # whole factor's, in the general path's order
        if reduced:
            stage = Reduced(self, contact_pins=True) if self.contacts else reduced
            o += stage.emit_accelerations(sym) + reduced.emit_accelerations(sym, end=True)
        fused = f"{sym}_accelerations, {sym}_end" if reduced else "nullptr, nullptr"
        # generalized-alpha's end on the Newton iteration's factor: where the reduced system
        # is the whole one (no pinned body: the factor's order and storage are the same)
        if reduced and not reduced.pinned:
            o += ["#if LEGSIM_WITH_GENERALIZED_ALPHA"] + reduced.emit_end_factored(sym) + ["#endif"]
            fused += f", LEGSIM_KERNEL_NEWTON({sym}_end_factored)"
        else:
            fused += ", nullptr"
        return "\n".join(o) + "\n" + self.emit_tables(sym, f"{sym}_dynamics", f"{sym}_newton", f"{sym}_factored",
                                                    fused)

    def emit_slide(self, sym):
        """A stance with one sliding foot (slide): RK4's stage solve alone (Kernel::accelerations,
        Reduced with the stuck feet as pins and the friction as one column); the rest of the
        table empty (the layout's joint kernel serves every other solve)."""
        stage = Reduced(self, contact_pins=True)
        o = stage.emit_accelerations(sym)
        t = self.emit_tables(sym, "nullptr", "nullptr", "nullptr", f"{sym}_accelerations, nullptr, nullptr")
        for f in ("rows", "factor", "forward", "backward", "solve", "j_times", "jt_times"):
            t = t.replace(f"{sym}_{f},", "nullptr,")
        return "\n".join(o) + "\n" + t

    def emit_tables(self, sym, dynamics, newton, factored, reduced="nullptr, nullptr, nullptr"):
        o = []
        sig = ", ".join(f"{{{KIND[j['kind']]}, {j['body'][0]}, {j['body'][1]}}}" for j in self.joints)
        o.append(f"const int8_t {sym}_joint[][3] = {{{sig}}};")
        o.append(f"const uint8_t {sym}_perm[] = {{{', '.join(map(str, self.perm))}}};")
        o.append(f"const uint8_t {sym}_first[] = {{{', '.join(map(str, self.first))}}};")
        cb = ", ".join(str(c["body"]) for c in self.contacts) or "-1"
        o.append(f"const int8_t {sym}_contact[] = {{{cb}}};")
        ab = ", ".join(f"{{{j}, {c}, {r}}}" for j, c, r in self.actuators) or "{-1, -1, -1}"
        o.append(f"const int8_t {sym}_actuator[][3] = {{{ab}}};")
        o.append(f"const Kernel {sym} = {{\"{self.name}\", {self.nb}, {len(self.joints)}, {sym}_joint, "
                 f"{len(self.contacts)}, {sym}_contact, {len(self.actuators)}, {sym}_actuator, "
                 f"{self.m}, {sym}_perm, {sym}_first, {sym}_rows, {sym}_factor, {sym}_forward, {sym}_backward, "
                 f"{sym}_solve, {sym}_j_times, {sym}_jt_times, {dynamics}, "
                 f"{'nullptr' if newton == 'nullptr' or self.newton_fused else f'LEGSIM_KERNEL_NEWTON({newton})'}, "
                 f"{factored}, {reduced}, "
                 f"{f'LEGSIM_KERNEL_NEWTON({newton})' if newton != 'nullptr' and self.newton_fused else 'nullptr'}}};")
        return "\n".join(o) + "\n"


class Reduced(Kernel):
    """RK4's solves (a stage's accelerations; the step's end) in fewer rows. A body pinned to the frame by
    one revolute joint moves with its angle alone: its accelerations are
    qdd_b = G_b phidd_b + g_b, G_b = (say, -sax, 1) (the pin point's offset (sax, say)) and
    g_b = (gamma_r, gamma_r+1, 0) (the pin rows' gamma), which is every qdd that satisfies
    the pin's two rows. Put in M qdd + J^T lambda = Q and multiplied by G_b^T (G_b^T J_pin^T
    = 0), the pin rows and their multipliers drop out: the body keeps one coordinate with
    mass G_b^T M_b G_b = m say^2 + m sax^2 + J (the moment of inertia about the pin), force
    G_b^T (Q_b - M_b g_b), and the other rows' columns J_b G_b, their gamma less J_b g_b.
    The same accelerations as the whole system's (a Schur complement of it: its pivots are
    the whole factor's after the pin rows) with fewer operations: the leg's 16 rows become
    10. Not a factor the general path can use. The step's end (emit_accelerations with
    end) gets the pins' multipliers back from their bodies' x and y equations, and the
    whole factor's pivots as the reduced ones and the pin rows' own (eliminated before any
    other row on their body: from their entries of J W J^T alone).
    With contact_pins (a stance's stages), a stuck contact's two rows pin its foot the same
    way: their coefficients on the foot are E (1, 0, -s_y; 0, 1, s_x), E the ground's normal
    and tangent, so rows_pin (kernel.hpp) gives the pin's point s and its rows' gamma in the
    world axes E^-1 gamma, and the pin units serve as for a joint's pin. The general path's
    stance order does not eliminate the contact rows first, so these pivots are not the
    whole factor's: the stages use their own order (work) and the end keeps the contact
    rows (its condition estimate is the whole factor's)."""

    def __init__(self, k, contact_pins=False):
        self.name, self.nb, self.joints, self.contacts, self.actuators = k.name, k.nb, k.joints, k.contacts, k.actuators
        self.slide = k.slide
        self.full = k
        first_row, r = [], 0
        for j in k.joints:
            first_row.append(r)
            r += NROWS[j["kind"]]
        pinned = pinned_bodies(k.joints)
        # body -> its pin: the names of its point's offset (sx, sy) and of its rows' gamma in
        # the world axes (g0, g1), its two rows, and (a joint's) the joint
        self.pinned = {j["body"][0]: Pin(f"sax{n}", f"say{n}", f"gam{first_row[n]}", f"gam{first_row[n] + 1}",
                                         first_row[n], n)
                       for n, j in enumerate(k.joints) if j["kind"] == "revolute_to_frame" and j["body"][0] in pinned}
        # with contact_pins, a stuck contact's two rows pin its foot's point to the ground
        # (rows_pin, kernel.hpp): where its body has no pin and no other contact
        self.pin_defs = []
        if contact_pins:
            feet = [c["body"] for c in k.contacts]
            for c, b in enumerate(feet):
                if b in self.pinned or feet.count(b) > 1 or c == k.slide:
                    continue
                r = k.contact_row[c]
                self.pinned[b] = Pin(f"psx{c}", f"psy{c}", f"pg{c}_0", f"pg{c}_1", r, None)
                a, e = [f"c{r}_0_{x}" for x in range(3)], [f"c{r + 1}_0_{x}" for x in range(3)]
                self.pin_defs.append(f"  real psx{c}, psy{c}, pg{c}_0, pg{c}_1;  // contact {c} as a pin (body {b})")
                self.pin_defs.append(f"  rows_pin({', '.join(a + e)}, gam{r}, gam{r + 1}, psx{c}, psy{c}, pg{c}_0, pg{c}_1);")
        self.orig = [i for i in range(k.m) if i not in self.full_pin_rows()]  # reduced row -> row
        self.rows, self.defs_e, self.defs_g = [], [], []  # the columns on the angles; the gammas
        for i in self.orig:
            bodies, slots = k.rows[i]
            new, gamma = [], []
            for s in range(2):
                b = bodies[s]
                if b < 0 or b not in self.pinned:  # run-time entries by the row's own names
                    new.append(tuple(f"c{i}_{s}_{x}" if v is V else v for x, v in enumerate(slots[s]))
                               if b >= 0 else slots[s])
                    continue
                pin = self.pinned[b]
                cx, cy, cp = (k.coef(i, s, x, True) for x in range(3))
                if cx[0] == 0 and cy[0] == 0 and not cp[1]:
                    new.append((0, 0, cp[0]))  # on the angle alone: a constant still
                else:
                    self.defs_e.append(f"  const real e{i}_{s} = "
                                     f"{product([(cx[0], cx[1] + [pin.sy]), (-cy[0], cy[1] + [pin.sx]), cp])};")
                    new.append((0, 0, f"e{i}_{s}"))
                gamma += [(cx[0], cx[1] + [pin.g0]), (cy[0], cy[1] + [pin.g1])]
            self.rows.append((bodies, tuple(new)))
            if any(c != 0 for c, _ in gamma):
                self.defs_g.append(f"  const real gr{i} = gam{i} - ({product(gamma)});")
            else:
                self.defs_g.append(f"  const real gr{i} = gam{i};")
        # the whole system's order without the pin rows (which it eliminates first): the
        # same pivots after them, to round-off. With contact pins the whole order does not
        # eliminate them first (the general path's stance order): the reduced system's own
        # order then, whichever of it, reverse Cuthill-McKee and minimum degree does the
        # least work (a stage needs no pivot of the whole factor)
        at = {i: r for r, i in enumerate(self.orig)}
        whole = [at[i] for i in k.row_at if i in at]
        if not self.pin_defs:
            self.structure(len(self.rows), whole)
            return
        m = len(self.rows)
        share = [[any(x >= 0 and x == y for x in self.rows[i][0] for y in self.rows[j][0])
                  for j in range(m)] for i in range(m)]
        best = None
        for order in (whole, rcm_order(m, share), min_degree_order(m, share)):
            self.structure(m, order)
            if best is None or self.work() < best[0]:
                best = (self.work(), order)
        self.structure(m, best[1])

    def w_name(self, b, k):
        return f"wr{b}" if b in self.pinned else f"w[{3 * b + k}]"

    def emit_accelerations(self, sym, end=False):
        """{sym}_accelerations: the fused solve of the reduced system, qdd alone. With end,
        {sym}_end: RK4's end of a step besides (Kernel::end): the largest |Phi| and |J qd|
        (no more where |Phi| is past tol, or |J qd| is and not project), the velocities'
        projection where |J qd| is past tol, the condition estimate, every row's multiplier
        and the joints' reactions."""
        k, nq = self.full, 3 * self.nb
        if end:
            o = [f"LEGSIM_STAGE_TARGETS legsim_status {sym}_end(const Model &model, "
                 "[[maybe_unused]] const DriverValues &dv, const VecQ &q, VecQ &qd, const VecQ &base, "
                 "Data &data, bool actuators, TrigCache *trig, real tol, bool project, real &residual, "
                 "real &drift, real &condition, VecR &lambda, VecQ &qdd, legsim_reaction *reaction) {"]
        else:
            o = [f"LEGSIM_STAGE_TARGETS legsim_status {sym}_accelerations(const Model &model, "
                 "[[maybe_unused]] const DriverValues &dv, const VecQ &q, const VecQ &qd, const VecQ &base, "
                 "Data &data, bool actuators, TrigCache *trig, VecQ &qdd) {"]
        o.append("  const real *w = model.minv;")
        o.append("  [[maybe_unused]] const real *mass = model.mass;  // (the pins' terms)")
        # a pinned body on its angle alone (rows.hpp's pin units)
        pinned_w = [f"  const real wr{b} = pin_inverse_inertia(mass + {3 * b}, XY{{{p.sx}, {p.sy}}});  // body {b} on its pin"
                    for b, p in sorted(self.pinned.items())]
        pinned_f = [f"  const real fr{b} = pin_force(mass + {3 * b}, XY{{{p.sx}, {p.sy}}}, {p.g0}, {p.g1}, Q{3 * b}, Q{3 * b + 1}, Q{3 * b + 2});"
                    for b, p in sorted(self.pinned.items())]
        # the pivot floor from the whole system's largest diagonal entry (kPivotFloor times
        # the same number as dynamics' floor; the reduced one's are no larger)
        floor = ["  real max_diag = 0;"]
        for p in range(k.m):
            floor.append(f"  const real F{p} = {k.a_entry(p, p, True)};")
            floor.append(f"  max_diag = F{p} > max_diag ? F{p} : max_diag;")
        if not end:
            o += k.rows_locals(self.shared_angles(), trig="grid_trig")
            # a stage needs no Phi, and some Jacobian entries serve only the floor below
            unused = [f"phi{i}" for i in range(k.m)] + [f"c{i}_{s}_{x}" for i in range(k.m) for s in range(2)
                                                      for x in range(3) if k.rows[i][0][s] >= 0
                                                      and k.rows[i][1][s][x] is V]
            o.append("  " + " ".join(f"(void){v};" for v in unused) + "  // not needed here")
            o += self.forces_locals(store=False) + self.pin_defs + pinned_w + pinned_f + self.defs_e + self.defs_g + self.t_locals() + floor
            o += self.factor_locals(True, "return LEGSIM_ERR_SINGULAR;", range_if=False)
            lname = lambda i: f"l{i}"  # noqa: E731
        else:
            # the positions' part first: the projection test and the factor need no velocities
            o += k.rows_locals(self.shared_angles(), part="q", trig="grid_trig")
            o.append("  real " + ", ".join(f"V{n} = qd[{n}]" for n in range(nq)) + ";  // projected below")
            # rows_max_residual's and velocity_drift's loops (rk4_step), in row order
            o.append("  real r = 0, jv;")
            for i in range(k.m):
                o.append(f"  if (!(std::abs(phi{i}) <= r)) r = std::abs(phi{i});")
            o.append("  residual = r;")
            o.append("  if (!(r <= tol)) return LEGSIM_OK;  // its positions need projecting: rk4_step's sequence")
            o.append("  r = 0;")
            for i in range(k.m):
                o.append(f"  jv = std::abs({k.j_expr(i, lambda n: f'V{n}', True)});")
                o.append("  r = jv > r ? jv : r;")
            o.append("  drift = r;")
            o.append("  const bool projected = !(r <= tol);")
            o.append("  if (projected && !project) return LEGSIM_OK;")
            o += pinned_w + self.defs_e + floor
            # the pivots' range: the reduced system's, which are the whole factor's after its
            # pin rows, and the pin rows' own (eliminated before any other row on their body:
            # their entries of J W J^T alone)
            fail = "{ condition = real(INFINITY); return LEGSIM_ERR_SINGULAR; }"
            o.append("  real pmin, pmax;")
            o += self.factor_locals(True, fail)
            pins = self.full_pin_rows()
            for p in range(k.m):
                if k.row_at[p] not in pins:
                    continue
                assert all(k.row_at[q] in pins for q in k.l_nz[p])
                for q in k.l_nz[p]:
                    o.append(f"  const real PT{p}_{q} = {k.a_entry(p, q, True)}, PL{p}_{q} = PT{p}_{q} / P{q};")
                sub = "".join(f" - PT{p}_{q} * PL{p}_{q}" for q in k.l_nz[p])
                o.append(f"  const real P{p} = F{p}{sub};  // (its diagonal entry: F{p} above)")
                o.append(f"  if (!(P{p} > floor)) {fail}")
                o.append(f"  pmin = P{p} < pmin ? P{p} : pmin;")
                o.append(f"  pmax = P{p} > pmax ? P{p} : pmax;")
            o.append("  condition = std::sqrt(pmax / pmin);")
            o += self.projection_locals()
            o += k.rows_locals(part="v", velocity=lambda n: f"V{n}")
            o += self.forces_locals() + pinned_f + self.defs_g + self.t_locals()
            lname = lambda i: f"l{self.orig[i]}"  # noqa: E731  (the whole system's row)
        o += [f"  const real b{i} = {self.j_expr(i, lambda n: f't{n}', True)} - gr{self.orig[i]};"
              for i in range(self.m)]
        slide = self.slide is not None and not end
        # with a sliding foot, x = A^-1 b first (friction_locals gives the multipliers)
        o += self.solve_locals(lambda i: f"b{i}", lambda i: f"const real x{i}" if slide else f"const real {lname(i)}")
        if slide:
            o += self.friction_locals()
        o.append("  real z = 0;  // x * 0 is NaN for an infinite or NaN x only")
        for n in range(nq):
            b, x = divmod(n, 3)
            jt = self.jt_expr(n, lambda i: lname(i), True)
            if slide and b == k.contacts[self.slide]["body"]:
                o.append(f"  qdd[{n}] = w[{n}] * (Q{n} - ({jt}) + fc[{x}] * ln);")
            elif b not in self.pinned:
                o.append(f"  qdd[{n}] = w[{n}] * (Q{n} - ({jt}));")
                o.append(f"  z += qdd[{n}] * real(0);")
            elif x == 2:
                p = self.pinned[b]
                o.append(f"  const real pdd{b} = wr{b} * (fr{b} - ({jt}));")
                o.append(f"  const XY acc{b} = pin_acceleration(XY{{{p.sx}, {p.sy}}}, {p.g0}, {p.g1}, pdd{b});")
                o.append(f"  const real qx{b} = acc{b}.x, qy{b} = acc{b}.y;")
                o.append(f"  qdd[{n - 2}] = qx{b};")
                o.append(f"  qdd[{n - 1}] = qy{b};")
                o.append(f"  qdd[{n}] = pdd{b};")
                o.append(f"  z += pdd{b} * real(0) + qx{b} * real(0) + qy{b} * real(0);")
        if end:
            # the pins' multipliers from their bodies' x and y equations, M qdd + J^T lambda = Q
            assert not self.pin_defs  # (a joint pin's rows are its body's x and y equations)
            for b, pin in sorted(self.pinned.items()):
                r = pin.r
                for e, axis in ((0, "x"), (1, "y")):
                    terms = []
                    for i in range(k.m):
                        if i in (r, r + 1):
                            continue
                        for s in range(2):
                            if k.rows[i][0][s] == b:
                                cc, vs = k.coef(i, s, e, True)
                                terms.append((cc, vs + [f"l{i}"]))
                    others = product(terms)
                    o.append(f"  const real l{r + e} = (Q{3 * b + e} - mass[{3 * b + e}] * q{axis}{b})"
                             + (f" - ({others});" if others != "0" else ";"))
                o.append(f"  z += l{r} * real(0) + l{r + 1} * real(0);")
            o += self.end_tail("the state's velocities now: J qd = 0 to round-off", ["drift = 0;"])
        else:
            o.append("  return z == z ? LEGSIM_OK : LEGSIM_ERR_DIVERGED;")
        o.append("}\n")
        return o

    def friction_locals(self):
        """The sliding contact's friction (mu_k N along the ground: M qdd = Q - J^T l + f l_n,
        f its friction column) as one Sherman-Morrison column, the general path's woodbury
        with one column: with x = A^-1 b (x<i>) and zz = A^-1 u, u = -J W f, l = x - zz x_n /
        (1 + zz_n) (l<i>, ln: the normal row's). Its body moves on its own coordinates."""
        k = self.full
        c = self.slide
        bs = k.contacts[c]["body"]
        assert bs not in self.pinned
        rn = self.orig.index(k.contact_row[c])
        o = [f"  real fc[3];  // contact {c}'s friction column, on body {bs}",
             f"  friction_column_at(model, data, {c}, s{bs}, c{bs}, fc);"]
        o += [f"  const real mf{x} = -(w[{3 * bs + x}] * fc[{x}]);" for x in range(3)]
        zero = set()
        for i in range(self.m):
            dots = [product([(self.coef(i, s, x, True)[0], self.coef(i, s, x, True)[1] + [f"mf{x}"]) for x in range(3)])
                    for s in range(2) if self.rows[i][0][s] == bs]
            if dots:
                o.append(f"  const real v{i} = {group(dots)};")
            else:
                zero.add(i)
        o += self.solve_locals(lambda i: f"v{i}", lambda i: f"const real zz{i}", tmp="y", zero=zero)
        o.append(f"  const real cs = 1 + zz{rn};")
        o.append("  if (!(std::abs(cs) > real(1e-9))) return LEGSIM_ERR_CONTACT;  // woodbury's floor (Painleve)")
        o.append(f"  const real ys = x{rn} / cs;")
        o += [f"  const real l{i} = x{i} - zz{i} * ys;" for i in range(self.m)]
        o.append(f"  const real ln = l{rn};")
        return o

    def emit_end_factored(self, sym):
        """{sym}_end_factored (Kernel::end_factored): generalized-alpha's end of a step, end's
        work on the factor given (a: the last Newton iteration's, at an iterate within tol of
        q, by position) instead of its own: |J qd| (drift), the velocities projected where it
        is past tol, once more where the first pass (on a factor not q's own) leaves it past
        tol (the general path's two passes), then every row's multiplier and the joints'
        reactions (not qdd: the step keeps the iteration's). For a structure without a pinned
        body only (its reduced system is the whole one, in the same order)."""
        assert not self.pinned
        k, nq = self.full, 3 * self.nb
        o = [f"LEGSIM_KERNEL_TARGETS legsim_status {sym}_end_factored(const Model &model, "
             "[[maybe_unused]] const DriverValues &dv, const VecQ &q, VecQ &qd, const VecQ &base, "
             "Data &data, bool actuators, TrigCache *trig, const real *a, real tol, real &drift, VecR &lambda, "
             "legsim_reaction *reaction) {"]
        o.append("  const real *w = model.minv;")
        o += k.rows_locals(part="q")
        o.append("  " + " ".join(f"(void)phi{i};" for i in range(k.m)) + "  // the velocity level: no Phi")
        o.append("  real " + ", ".join(f"V{n} = qd[{n}]" for n in range(nq)) + ";  // projected below")
        drift = ["  r = 0;"]
        for i in range(k.m):
            drift.append(f"  jv = std::abs({k.j_expr(i, lambda n: f'V{n}', True)});")
            drift.append("  r = jv > r ? jv : r;")
        o.append("  real r, jv;")
        o += drift
        o.append("  const bool projected = !(r <= tol);")
        for npass in range(2):
            o.append("  if (!(r <= tol)) {  // " + ("a pass" if npass == 0 else "a second pass"))
            o += ["  " + x for x in self.projection_locals(guard="", lval="a")]
            o += ["  " + x for x in drift]
            o.append("  }")
        o.append("  drift = r;")
        o += k.rows_locals(part="v", velocity=lambda n: f"V{n}")
        o += self.forces_locals() + self.defs_g + self.t_locals()
        o += [f"  const real b{i} = {self.j_expr(i, lambda n: f't{n}', True)} - gr{self.orig[i]};"
              for i in range(self.m)]
        o += self.solve_locals(lambda i: f"b{i}", lambda i: f"const real l{self.orig[i]}", lval="a")
        # qdd = M^-1 (Q - J^T lambda) is the iteration's, not this: no caller reads the end's.
        # It is finite where Q and the multipliers are (which it is made of), the status's test
        o.append("  real z = 0;  // x * 0 is NaN for an infinite or NaN x only")
        o += [f"  z += Q{n} * real(0);" for n in range(nq)]
        o += [f"  z += l{self.orig[i]} * real(0);" for i in range(self.m)]
        o += self.end_tail("the state's velocities now")
        o.append("}\n")
        return o

    def end_tail(self, note, also=()):
        """The ends' last lines: every row's multiplier and the joints' reactions out, the
        status (qdd not finite: LEGSIM_ERR_DIVERGED), and only then the projected velocities
        (with `also`), so that qd is written only when the whole call succeeds."""
        k = self.full
        o = [f"  lambda[{i}] = l{i};" for i in range(k.m)]
        o += k.reactions_locals()
        o.append("  if (!(z == z)) return LEGSIM_ERR_DIVERGED;")
        o.append(f"  if (projected) {{  // {note}")
        o.append("    " + " ".join(f"qd[{n}] = V{n};" for n in range(3 * self.nb)))
        o += [f"    {x}" for x in also]
        o.append("  }")
        o.append("  return LEGSIM_OK;")
        return o

    def t_locals(self):
        """M^-1 Q in the reduced coordinates: t<n> (a pinned body's on its angle alone)."""
        o = []
        for n in range(3 * self.nb):
            b, x = divmod(n, 3)
            if b not in self.pinned:
                o.append(f"  const real t{n} = w[{n}] * Q{n};")
            elif x == 2:
                o.append(f"  const real t{n} = wr{b} * fr{b};")
        return o

    def projection_locals(self, guard="if (projected) ", lval="L"):
        """Where guard holds: the velocities V<n> projected onto J V = 0, M-weighted, as the
        general path's project does it in the whole system (linear_solve.cpp), here in the
        reduced one (the same result to round-off): a pinned body's velocities v_b become
        its angle's rate u_b = wr_b G_b^T M_b v_b (the M-nearest G_b u_b, which meets its
        pin's rows), and with the reduced rows J_r, W_r (wr_b on a pinned body's angle):
        u <- u - W_r J_r^T (J_r W_r J_r^T)^-1 J_r u, the factor's, then v_b = G_b u_b. The
        whole projection is this one: it is M-orthogonal to the pins' G_b u, and the rest is
        the reduced problem. lval: the factor's, as solve_locals' (the array a: generalized-
        alpha's end on the Newton iteration's factor, a structure without a pinned body)."""
        assert lval == "L" or not self.pinned  # (a holds the whole system's factor)
        o = [f"  {guard}{{"]
        for b, p in sorted(self.pinned.items()):
            o.append(f"    const real ur{b} = pin_rate(mass + {3 * b}, XY{{{p.sx}, {p.sy}}}, wr{b}, V{3 * b}, V{3 * b + 1}, V{3 * b + 2});")
        u = lambda n: f"ur{n // 3}" if n // 3 in self.pinned else f"V{n}"  # noqa: E731
        o += [f"    const real pc{i} = {self.j_expr(i, u, True)};" for i in range(self.m)]
        o += ["  " + line for line in self.solve_locals(lambda i: f"pc{i}", lambda i: f"const real py{i}", lval=lval)]
        for n in range(3 * self.nb):
            b, x = divmod(n, 3)
            jt = self.jt_expr(n, lambda i: f"py{i}", True)
            if b not in self.pinned:
                if jt != "0":
                    o.append(f"    V{n} -= w[{n}] * ({jt});")
            elif x == 2:
                p = self.pinned[b]
                o.append(f"    const real up{b} = ur{b} - wr{b} * ({jt});")
                o.append(f"    const XY vel{b} = pin_velocity(XY{{{p.sx}, {p.sy}}}, up{b});")
                o.append(f"    V{n - 2} = vel{b}.x, V{n - 1} = vel{b}.y, V{n} = up{b};")
        o.append("  }")
        return o

    def shared_angles(self):
        """body -> the body whose angle a prismatic joint keeps equal to its own (the rod ->
        its cylinder), where that one's pair comes first (rows_locals' order)."""
        return {j["body"][1]: j["body"][0] for j in self.joints
                if j["kind"] == "prismatic" and 0 <= j["body"][0] < j["body"][1]}

    def full_pin_rows(self):
        """The whole system's rows of the pins (those the reduced system leaves out)."""
        return {p.r + e for p in self.pinned.values() for e in (0, 1)}


# Every generated function carries LEGSIM_KERNEL_TARGETS (kernel.hpp): on x86-64 with GCC
# and glibc, a baseline and an AVX copy, the same values bit for bit.


def load_structure(path):
    """[(variant, model)] of a model file, from `legsim_model FILE --emit-structure`'s JSON:
    per model its bodies, joints (kind, body pair), actuators (joint) and contacts (body)."""
    with open(path, encoding="utf-8") as f:
        return [(v["name"], v["model"]) for v in json.load(f)["variants"]]


def generate(paths, default_only=False, stance_kernels=True, fused_max_rows=None, reduced=True):
    """The generated file's text. Fused solves (dynamics, newton) go to each model's main
    system only (its joint rows if it has no contacts, else its stance kernel) and, with
    fused_max_rows, only to kernels of at most that many rows: each is straight-line code
    whose size grows with the square of the factor's fill (the robot's stance kernel's
    pair is about 120 KB on a Cortex-M7)."""
    kernels, seen, slides, sym_of = [], set(), [], {}
    for path in paths:
        stem = os.path.splitext(os.path.basename(path))[0]
        variants = load_structure(path)
        for variant, model in variants[:1] if default_only else variants:
            for stance in (False, True) if model.get("contacts") and stance_kernels else (False,):
                k = Kernel(f"{stem} {variant}" + (" stance" if stance else ""), model, stance)
                k.fused = ((stance or not model.get("contacts"))
                           and (fused_max_rows is None or k.m <= fused_max_rows))
                k.reduced = reduced
                # a cross build's newton takes Q and leaves the residual to its caller: on a
                # Cortex-M4F they cost flash and instructions (1,016 B; the leg's step 8,040 ->
                # 8,110); the core leaves its caller out there (LEGSIM_KERNELS_NEWTON_FUSED)
                k.newton_fused = not default_only
                if separator(k.rows) is not None:
                    continue  # the general path's Schur complement on the box serves it
                if k.signature() not in seen:
                    seen.add(k.signature())
                    sym_of[k.signature()] = f"kernel_{stem}_{variant}" + ("_stance" if stance else "")
                    kernels.append((sym_of[k.signature()], k))
                    # RK4's stages with one foot sliding, the others stuck (a robot's: two
                    # contacts or more, on bodies no joint pins)
                    pinned = pinned_bodies(k.joints)
                    if stance and reduced and len(k.contacts) > 1:
                        for c, con in enumerate(k.contacts):
                            if con["body"] not in pinned:
                                ks = Kernel(f"{k.name} slide {c}", model, True, slide=c)
                                joints = sym_of.get(Kernel("", model).signature())
                                if joints:
                                    slides.append((f"kernel_{stem}_{variant}_slide{c}", ks, joints))
    o = ["// Generated by firmware_core/tools/kernel_codegen.py from "
         + (", ".join(os.path.basename(p) for p in paths) or "no model (LEGSIM_KERNELS=OFF)")
         + ". Do not edit.",
         "#include <cmath>", "", "#include \"planar/kernel.hpp\"", "#include \"planar/rows.hpp\"", "",
         "// A build without generalized-alpha (LEGSIM_WITH_GENERALIZED_ALPHA 0) has no use for its",
         "// fused Newton iteration: left out, its flash saved.",
         "#if LEGSIM_WITH_GENERALIZED_ALPHA",
         "#define LEGSIM_KERNEL_NEWTON(f) f",
         "#else",
         "#define LEGSIM_KERNEL_NEWTON(f) nullptr",
         "#endif", "", "namespace legsim {",
         "namespace {", ""]
    for sym, k in kernels:
        o.append(f"#if LEGSIM_MAX_BODIES >= {k.nb} && LEGSIM_MAX_JOINTS >= {len(k.joints)} && "
                 f"LEGSIM_MAX_CONTACTS >= {len(k.contacts)}")
        nl = sum(len(x) for x in k.l_nz)
        na = sum(sum(r[:p]) for p, r in enumerate(k.a_nz))
        o.append(f"// {k.name}: {k.m} rows, {na} off-diagonal non-zeros of J W J^T, "
                 f"{nl} of its factor")
        o.append(k.emit(sym))
        o.append("#endif\n")
    for sym, k, _ in slides:
        o.append(f"#if LEGSIM_MAX_BODIES >= {k.nb} && LEGSIM_MAX_JOINTS >= {len(k.joints)} && "
                 f"LEGSIM_MAX_CONTACTS >= {len(k.contacts)} && LEGSIM_KERNELS_REDUCED")
        o.append(f"// {k.name}: RK4's stage alone, {k.m} rows")
        o.append(k.emit_slide(sym))
        o.append("#endif\n")
    o.append("const Kernel *const kKernels[] = {")
    for sym, k in kernels:
        o.append(f"#if LEGSIM_MAX_BODIES >= {k.nb} && LEGSIM_MAX_JOINTS >= {len(k.joints)} && "
                 f"LEGSIM_MAX_CONTACTS >= {len(k.contacts)}")
        o.append(f"    &{sym},")
        o.append("#endif")
    o.append("    nullptr};")
    o.append("// a joint kernel -> its stance's stages with contact `slide` sliding")
    o.append("struct Slide { const Kernel *joints; int slide; const Kernel *stage; };")
    o.append("const Slide kSlides[] = {")
    for sym, k, stance in slides:
        o.append(f"#if LEGSIM_MAX_BODIES >= {k.nb} && LEGSIM_MAX_JOINTS >= {len(k.joints)} && "
                 f"LEGSIM_MAX_CONTACTS >= {len(k.contacts)} && LEGSIM_KERNELS_REDUCED")
        o.append(f"    {{&{stance}, {k.slide}, &{sym}}},")
        o.append("#endif")
    o.append("    {nullptr, -1, nullptr}};")
    o.append("}  // namespace\n")
    o.append("""const Kernel *kernel_find_slide(const Kernel *joints, int slide) {
  for (const Slide *s = kSlides; s->joints; ++s)
    if (s->joints == joints && s->slide == slide) return s->stage;
  return nullptr;
}
""")
    o.append("""const Kernel *kernel_find(const Model &model, bool stance) {
  const int nc = stance ? model.nc : 0;
  if (stance && nc == 0) return nullptr;
  for (const Kernel *const *k = kKernels; *k; ++k) {
    const Kernel &kn = **k;
    bool same = kn.nb == model.nb && kn.nj == model.nj && kn.nc == nc && kn.mj == model.m + 2 * nc;
    for (int j = 0; same && j < model.nj; ++j)
      same = kn.joint[j][0] == int(model.joint[j].kind) && kn.joint[j][1] == model.joint[j].a &&
             kn.joint[j][2] == model.joint[j].b;
    for (int c = 0; same && c < nc; ++c) same = kn.contact_body[c] == model.contact[c].body;
    // the reduced solves apply the actuators' forces: their joints are part of the structure
    same = same && (!kn.accelerations || kn.na == model.na);
    for (int a = 0; same && kn.accelerations && a < model.na; ++a) same = kn.actuator[a][0] == model.act[a].joint;
    if (same) return &kn;
  }
  return nullptr;
}
""")
    o.append("}  // namespace legsim")
    return "\n".join(o) + "\n"


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("toml", nargs="*", help="structure files (legsim_model --emit-structure); "
                   "none: an empty table (kernel_find finds nothing)")
    p.add_argument("--default-only", action="store_true",
                   help="each file's default variant only (cross builds: the one an image uses)")
    p.add_argument("--no-stance", action="store_true",
                   help="no stance kernels (the robot's joints and stuck feet): less flash")
    p.add_argument("--fused-max-rows", type=int, default=None, metavar="N",
                   help="fused solves only for kernels of at most N rows (default: no limit)")
    p.add_argument("--no-reduced", action="store_true",
                   help="no reduced solves for RK4 (Kernel::accelerations, end): less flash")
    p.add_argument("--out", required=True, help="the C++ source to write")
    args = p.parse_args(argv)
    try:
        text = generate(args.toml, args.default_only, not args.no_stance, args.fused_max_rows, not args.no_reduced)
    except (OSError, ValueError, KeyError) as e:
        print(f"kernel_codegen: error: {e}", file=sys.stderr)
        return 1
    with open(args.out, "w", encoding="utf-8") as f:
        f.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
