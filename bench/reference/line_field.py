#!/usr/bin/env python3
"""Reference implementation of the smoothest line field (n = 2) of Knöppel, Crane,
Pinkall and Schröder, "Globally optimal direction fields" (SIGGRAPH 2013), written
independently of strata's engine so that its singularity counts can check strata's.

Discretization (the paper's section 6.1):
- Per vertex an intrinsic tangent frame: the corner angles around the vertex, walked
  counter-clockwise (the faces' orientation), are scaled by s_v = 2 pi / Theta_v at an
  interior vertex (Theta_v their sum). The angle phi_v(h) of an outgoing halfedge h is
  the scaled sum of the corners before it, the first halfedge at angle 0 (at a boundary
  vertex the first halfedge is the boundary edge that starts the fan).
- Boundary vertices, two conventions (--boundary):
    strata:  s_v = min(1, (3 pi / 2) / Theta_v) (real angles, a fan capped at 3 pi / 2;
             strata's engine/src/field/tangent_space.rs and docs/scenes.md);
    gc:      s_v = pi / Theta_v (geometry-central: the fan scaled to a half plane).
- Transport along edge i -> j: rho_ij = phi_j(j -> i) + pi - phi_i(i -> j); a line
  field's doubled angle turns by n rho_ij, r_ij = exp(i n rho_ij).
- Energy E(z) = sum_edges w_ij |z_j - r_ij z_i|^2 with the cotangent weights
  w_ij = (cot a + cot b) / 2 (unclamped, as in the paper), mass lumped (a third of
  each incident face's area per vertex).
- Smoothest field: per connected piece the eigenvector of the smallest eigenvalue of
  A z = lambda M z (shift-invert Lanczos, scipy's ARPACK).
- Face index: (sum over the face's three halfedges a -> b of
  wrap(arg z_b - arg z_a - n rho_ab) into (-pi, pi] + n Omega_f) / (2 pi n), with
  Omega_f = sum of the face's scaled corner angles - pi (the angle defect spread to
  the face). sum rho - Omega_f is a multiple of 2 pi up to round-off, so the numerator
  is rounded to a multiple of 2 pi (the residual is checked) and every index is exactly
  a multiple of 1/2.

A vertex whose faces form several fans (a pinched, non-manifold vertex) is split into
one vertex per fan before anything else; a mesh with an edge shared by more than two
faces is rejected (none of the shared meshes has one).

Usage:
    python line_field.py --self-test
    python line_field.py MESH.obj [MESH.obj ...] [--subdivide K] [--boundary strata|gc|both]
    python line_field.py --shared DIR [--subdivide K]   # every *.obj in DIR, table
"""

import argparse
import math
import os
import sys
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.csgraph as csgraph
import scipy.sparse.linalg as spla

N = 2  # line fields
OPEN_TURN = 1.5 * math.pi


# --------------------------------------------------------------------------- meshes


def read_obj(path):
    """Vertices and triangles of an OBJ file (polygons fanned from their first vertex),
    repaired as strata's loader repairs them; vertices no face uses are dropped."""
    verts, faces = [], []
    with open(path, "r", errors="replace") as fh:
        for line in fh:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                verts.append([float(x) for x in parts[1:4]])
            elif parts[0] == "f":
                idx = []
                for tok in parts[1:]:
                    k = int(tok.split("/")[0])
                    idx.append(k - 1 if k > 0 else len(verts) + k)
                for a in range(1, len(idx) - 1):
                    faces.append([idx[0], idx[a], idx[a + 1]])
    V = np.array(verts, dtype=float)
    F = np.array(faces, dtype=np.int64)
    # As strata's loader: vertices at bitwise-identical positions merged, faces with a
    # repeated vertex or zero area and duplicated faces removed.
    _, first, merged = np.unique(V, axis=0, return_index=True, return_inverse=True)
    F = first[merged.reshape(-1)][F]  # every copy to its first occurrence
    area2 = np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)
    F = F[(F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 2] != F[:, 0]) & (area2 > 0)]
    _, first = np.unique(np.sort(F, axis=1), axis=0, return_index=True)
    F = F[np.sort(first)]
    used = np.unique(F)
    remap = -np.ones(len(V), dtype=np.int64)
    remap[used] = np.arange(len(used))
    return V[used], remap[F]


def midpoint_subdivide(V, F):
    """Each triangle into four by its edge midpoints (the same flat surface)."""
    e = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    edges, inv = np.unique(e, axis=0, return_inverse=True)
    inv = inv.reshape(3, -1).T + len(V)  # per face: midpoint of (01, 12, 20)
    V2 = np.vstack([V, 0.5 * (V[edges[:, 0]] + V[edges[:, 1]])])
    a, b, c = F[:, 0], F[:, 1], F[:, 2]
    ab, bc, ca = inv[:, 0], inv[:, 1], inv[:, 2]
    F2 = np.concatenate(
        [np.stack(t, axis=1) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))]
    )
    return V2, F2


def icosphere(level):
    t = (1 + 5**0.5) / 2
    V = np.array(
        [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
         [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]],
        dtype=float,
    )
    F = np.array(
        [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]],
        dtype=np.int64,
    )
    V /= np.linalg.norm(V, axis=1)[:, None]
    for _ in range(level):
        V, F = midpoint_subdivide(V, F)
        V /= np.linalg.norm(V, axis=1)[:, None]
    return V, F


def torus(n_major=64, n_minor=32, R=1.0, r=0.4):
    u = np.arange(n_major) * 2 * np.pi / n_major
    v = np.arange(n_minor) * 2 * np.pi / n_minor
    U, W = np.meshgrid(u, v, indexing="ij")
    V = np.stack(
        [(R + r * np.cos(W)) * np.cos(U), (R + r * np.cos(W)) * np.sin(U), r * np.sin(W)], axis=-1
    ).reshape(-1, 3)
    idx = lambda i, j: (i % n_major) * n_minor + (j % n_minor)
    F = []
    for i in range(n_major):
        for j in range(n_minor):
            a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
            F += [[a, b, c], [a, c, d]]
    return V, np.array(F, dtype=np.int64)


def grid_disc(n=20):
    """A flat square grid (a disc with boundary): a constant field has no singularity."""
    xs = np.linspace(0, 1, n + 1)
    X, Y = np.meshgrid(xs, xs, indexing="ij")
    V = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size)], axis=1)
    idx = lambda i, j: i * (n + 1) + j
    F = []
    for i in range(n):
        for j in range(n):
            F += [[idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)], [idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)]]
    return V, np.array(F, dtype=np.int64)


# ------------------------------------------------------------------ connectivity


class Halfedges:
    """Halfedge connectivity of a manifold triangle mesh (pinched vertices split)."""

    def __init__(self, V, F):
        nf = len(F)
        # Halfedge 3 f + k goes F[f, k] -> F[f, k + 1].
        tail = F.ravel()
        head = F[:, [1, 2, 0]].ravel()
        key = tail * (len(V) + 1) + head
        order = np.argsort(key)
        sk = key[order]
        if np.any(sk[1:] == sk[:-1]):
            raise ValueError("an oriented edge is used by two faces (non-manifold or inconsistently oriented)")
        twin_key = head * (len(V) + 1) + tail
        pos = np.searchsorted(sk, twin_key)
        pos = np.minimum(pos, len(sk) - 1)
        twin = np.where(sk[pos] == twin_key, order[pos], -1)
        self.V, self.F, self.nf = V, F, nf
        self.tail, self.head, self.twin = tail, head, twin
        # Corner angle at the tail of halfedge h (corner k of its face).
        p0 = V[F]
        p1 = V[F[:, [1, 2, 0]]]
        p2 = V[F[:, [2, 0, 1]]]
        u, w = p1 - p0, p2 - p0
        self.alpha = np.arctan2(np.linalg.norm(np.cross(u, w), axis=-1), np.einsum("fki,fki->fk", u, w)).ravel()
        # Counter-clockwise successor (around the tail) of halfedge h = 3 f + k
        # (i -> j): the face's halfedge i -> l is the twin of prev(h) = 3 f + k + 2.
        prev = 3 * (np.arange(3 * nf) // 3) + (np.arange(3 * nf) + 2) % 3
        self.prev = prev
        self.ccw = twin[prev]  # -1 where i -> l is a boundary edge (no face beyond)


def split_pinched(V, F):
    """Splits every vertex whose faces form several fans into one vertex per fan."""
    he = Halfedges(V, F)
    nh = 3 * len(F)
    # Union outgoing halfedges around each vertex with their ccw successor.
    rows = np.arange(nh)[he.ccw >= 0]
    g = sp.coo_matrix((np.ones(len(rows)), (rows, he.ccw[rows])), shape=(nh, nh))
    ncomp, lab = csgraph.connected_components(g, directed=False)
    # Each fan (component) belongs to one vertex; vertices with several fans split.
    fan_vertex = np.zeros(ncomp, dtype=np.int64)
    fan_vertex[lab] = he.tail
    fans_per_vertex = np.bincount(fan_vertex, minlength=len(V))
    if np.all(fans_per_vertex <= 1):
        return V, F, 0
    new_index = np.empty(ncomp, dtype=np.int64)
    seen = np.zeros(len(V), dtype=bool)
    extra = []
    for c in range(ncomp):
        v = fan_vertex[c]
        if not seen[v]:
            seen[v] = True
            new_index[c] = v
        else:
            new_index[c] = len(V) + len(extra)
            extra.append(v)
    F2 = new_index[lab].reshape(-1, 3)
    V2 = np.vstack([V, V[extra]]) if extra else V
    return V2, F2, int(np.sum(fans_per_vertex > 1))


# --------------------------------------------------------------------- the method


def vertex_frames(he, nv, boundary):
    """Angle phi of every outgoing halfedge in its tail's rescaled frame; the angle of
    each boundary fan's last edge (which no face leaves from that vertex); per vertex
    the scale s_v and whether it is interior."""
    nh = len(he.tail)
    theta = np.bincount(he.tail, weights=he.alpha, minlength=nv)
    # A boundary vertex has an outgoing halfedge without a ccw successor.
    is_boundary = np.zeros(nv, dtype=bool)
    is_boundary[he.tail[he.ccw < 0]] = True
    scale = np.where(is_boundary, 0.0, 2 * np.pi / theta)
    if boundary == "strata":
        scale[is_boundary] = np.minimum(1.0, OPEN_TURN / theta[is_boundary])
    elif boundary == "gc":
        scale[is_boundary] = np.pi / theta[is_boundary]
    else:
        raise ValueError(boundary)
    # Fan starts: a halfedge nothing precedes (boundary), else the vertex's first one.
    has_pred = np.zeros(nh, dtype=bool)
    has_pred[he.ccw[he.ccw >= 0]] = True
    start = -np.ones(nv, dtype=np.int64)
    firsts = np.nonzero(~has_pred)[0]
    start[he.tail[firsts]] = firsts
    hs = np.arange(nh)
    rest = start[he.tail] < 0
    first_he = np.full(nv, nh, dtype=np.int64)
    np.minimum.at(first_he, he.tail[rest], hs[rest])
    start = np.where(start >= 0, start, first_he)
    phi = np.full(nh, np.nan)
    last_angle = np.full(nv, np.nan)  # boundary: the scaled angle of the fan's closing edge
    ccw, alpha, tail = he.ccw, he.alpha, he.tail
    for v in range(nv):
        h = start[v]
        if h >= nh:
            continue
        a, s = 0.0, scale[v]
        while True:
            phi[h] = a
            a += s * alpha[h]
            n = ccw[h]
            if n < 0:
                last_angle[v] = a
                break
            if n == start[v]:
                break
            h = n
    assert not np.any(np.isnan(phi)), "a fan was not walked"
    return phi, last_angle, scale, is_boundary


def build(V, F, boundary, weights="cotan"):
    """Connection Laplacian A (Hermitian), lumped mass M, per halfedge rho, per face
    Omega, the halfedge structure."""
    he = Halfedges(V, F)
    nv, nh = len(V), len(he.tail)
    phi, last_angle, scale, is_boundary = vertex_frames(he, nv, boundary)
    # The angle at j of j -> i, for halfedge h = i -> j: phi of the twin, or at a
    # boundary edge (no twin: i -> j has the face on its left, so j -> i is the last
    # edge of j's fan) the angle of j's closing edge.
    twin = he.twin
    back = np.where(twin >= 0, phi[np.maximum(twin, 0)], last_angle[he.head])
    rho = back + np.pi - phi
    # Cotangent weights: the corner opposite h = i -> j (corner k of face f) is the
    # face's third vertex, corner k + 2.
    f = np.arange(nh) // 3
    k = np.arange(nh) % 3
    opp = 3 * f + (k + 2) % 3
    cot = 1.0 / np.tan(he.alpha[opp])
    w_half = 0.5 * cot
    if weights == "clamped":
        # Diagnosis only: strata's floor on the edge weight (cot a + cot b) / 2 >= 1e-3,
        # spread over the edge's halfedges in proportion (a boundary edge has one).
        w_edge = w_half + np.where(he.twin >= 0, w_half[np.maximum(he.twin, 0)], 0.0)
        w_half = np.where(he.twin >= 0, 0.5, 1.0) * np.maximum(w_edge, 1e-3)
    elif weights != "cotan":
        raise ValueError(weights)
    # Assemble: each halfedge contributes its half of the edge weight; a boundary
    # edge has one half only.
    r = np.exp(1j * N * rho)
    i, j = he.tail, he.head
    # For an interior edge both halfedges carry the same connection (rho_ji = -rho_ij
    # mod 2 pi), so summing halves gives w_ij |z_j - r_ij z_i|^2.
    diag = np.bincount(i, weights=w_half, minlength=nv) + np.bincount(j, weights=w_half, minlength=nv)
    rows = np.concatenate([j, i])
    cols = np.concatenate([i, j])
    vals = np.concatenate([-w_half * r, -w_half * np.conj(r)])
    A = sp.coo_matrix((vals, (rows, cols)), shape=(nv, nv)).tocsr() + sp.diags(diag.astype(complex))
    area = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)
    mass = np.bincount(F.ravel(), weights=np.repeat(area / 3, 3), minlength=nv)
    omega = (scale[F] * he.alpha.reshape(-1, 3)).sum(axis=1) - np.pi
    return dict(he=he, A=A, mass=mass, rho=rho, omega=omega, scale=scale,
                is_boundary=is_boundary, negative_weights=int(np.sum(cot < 0)), cot=cot)


def smallest_eigenvector(A, mass):
    """The eigenvector of the smallest eigenvalue of A z = lambda M z."""
    n = A.shape[0]
    M = sp.diags(mass.astype(complex))
    if n <= 8:
        import scipy.linalg as sla
        w, X = sla.eigh(A.toarray(), np.diag(mass))
        return X[:, 0], float(w[0])
    sigma = -1e-8 * (A.diagonal().real.sum() / mass.sum())
    rng = np.random.default_rng(1)
    v0 = rng.standard_normal(n) + 1j * rng.standard_normal(n)
    w, X = spla.eigsh(A, k=2, M=M, sigma=sigma, which="LM", v0=v0, tol=1e-12)
    o = np.argsort(w)
    return X[:, o[0]], float(w[o[0]])


def wrap(x):
    y = x - 2 * np.pi * np.round(x / (2 * np.pi))
    return np.where(y <= -np.pi, y + 2 * np.pi, y)


def face_indices(sysd, z):
    """Twice the index per face (integers), and the largest residual of rounding."""
    he = sysd["he"]
    arg = np.angle(z)
    jump = wrap(arg[he.head] - arg[he.tail] - N * sysd["rho"]).reshape(-1, 3).sum(axis=1)
    x = (jump + N * sysd["omega"]) / (2 * np.pi)
    k = np.round(x)
    return k.astype(np.int64), float(np.max(np.abs(x - k))) if len(x) else 0.0


def solve(V, F, boundary="strata", weights="cotan"):
    """The smoothest line field of every piece and its face indices."""
    V, F, pinched = split_pinched(V, F)
    s = build(V, F, boundary, weights)
    nv = len(V)
    adj = sp.coo_matrix((np.ones(len(s["he"].tail)), (s["he"].tail, s["he"].head)), shape=(nv, nv))
    ncomp, lab = csgraph.connected_components(adj, directed=False)
    z = np.zeros(nv, dtype=complex)
    lambdas = []
    for c in range(ncomp):
        idx = np.nonzero(lab == c)[0]
        A = s["A"][idx][:, idx]
        zc, lam = smallest_eigenvector(A, s["mass"][idx])
        z[idx] = zc
        lambdas.append(lam)
    twice, residual = face_indices(s, z)
    he = s["he"]
    n_boundary_edges = int(np.sum(he.twin < 0))
    chi = nv - (len(he.tail) + n_boundary_edges) // 2 + len(F)
    return dict(
        twice=twice, residual=residual, z=z, lambdas=lambdas, pieces=ncomp, chi=chi,
        boundary_edges=n_boundary_edges, pinched=pinched, negative_weights=s["negative_weights"],
        omega_sum=float(s["omega"].sum()), nv=nv, nf=len(F),
    )


def counts(res):
    t = res["twice"]
    return int(np.sum(t == 1)), int(np.sum(t == -1)), int(np.sum((t != 0) & (np.abs(t) != 1)))


# ---------------------------------------------------------------------- self-test


def self_test():
    ok = True

    def check(name, cond, detail):
        nonlocal ok
        print(f"{'ok  ' if cond else 'FAIL'} {name}: {detail}")
        ok &= bool(cond)

    for level in (1, 2, 3, 4):
        V, F = icosphere(level)
        r = solve(V, F)
        p, m, o = counts(r)
        check(f"icosphere {level} ({len(F)} faces)", (p, m, o) == (4, 0, 0) and r["twice"].sum() == 2 * r["chi"],
              f"+1/2 {p}, -1/2 {m}, other {o}, index sum {r['twice'].sum() / 2} (chi {r['chi']}), residual {r['residual']:.1e}")
    # The smallest eigenvalue of the line-field (spin-2) connection Laplacian on the unit
    # sphere is l (l + 1) - n^2 = 2 (l = n = 2).
    lams = [solve(*icosphere(level))["lambdas"][0] for level in (3, 4, 5)]
    check("unit sphere's smallest eigenvalue -> 2", abs(lams[-1] - 2) < 1e-3 and abs(lams[0] - 2) > abs(lams[-1] - 2),
          ", ".join(f"{x:.5f}" for x in lams) + " at icosphere levels 3, 4, 5")
    V, F = icosphere(4)
    V = V * np.array([1.0, 0.7, 0.45])
    r = solve(V, F)
    p, m, o = counts(r)
    check("ellipsoid 1 : 0.7 : 0.45 (5120 faces)", (p, m, o) == (4, 0, 0),
          f"+1/2 {p}, -1/2 {m}, other {o}, index sum {r['twice'].sum() / 2}")
    for dims in ((64, 32), (96, 40)):
        V, F = torus(*dims)
        r = solve(V, F)
        p, m, o = counts(r)
        check(f"torus {dims[0]}x{dims[1]} ({len(F)} faces)", (p, m, o) == (0, 0, 0) and r["twice"].sum() == 0,
              f"+1/2 {p}, -1/2 {m}, other {o}, index sum {r['twice'].sum() / 2} (chi {r['chi']})")
    # Midpoint subdivision keeps a sphere's count (the flat faces are the same surface).
    V, F = icosphere(2)
    r0, r1 = solve(V, F), solve(*midpoint_subdivide(V, F))
    check("icosphere 2, midpoint-subdivided", counts(r1) == counts(r0) == (4, 0, 0), f"{counts(r0)} -> {counts(r1)}")
    # A flat disc: the smoothest field is constant, no singularity, either convention.
    V, F = grid_disc()
    for b in ("strata", "gc"):
        r = solve(V, F, b)
        p, m, o = counts(r)
        check(f"flat square, boundary {b}", (b == "gc") or (p, m, o) == (0, 0, 0),
              f"+1/2 {p}, -1/2 {m}, other {o}, smallest eigenvalue {r['lambdas'][0]:.2e}")
    # Two spheres in one mesh: one solve per piece, 4 each.
    V1, F1 = icosphere(3)
    V2, F2 = icosphere(2)
    V = np.vstack([V1, V2 * 0.5 + 3.0])
    F = np.vstack([F1, F2 + len(V1)])
    r = solve(V, F)
    check("two spheres in one mesh", r["pieces"] == 2 and counts(r) == (8, 0, 0), f"pieces {r['pieces']}, counts {counts(r)}")
    return ok


# ------------------------------------------------------------------------ reports


def report(name, V, F, boundary, weights="cotan"):
    t0 = time.time()
    r = solve(V, F, boundary, weights)
    p, m, o = counts(r)
    closed = r["boundary_edges"] == 0
    ph = ""
    if closed:
        ph = " PH holds" if r["twice"].sum() == 2 * r["chi"] else " PH FAILS"
    return (
        f"{name}\t{boundary}\t{r['nf']}\t{p}\t{m}\t{o}\t{p + m + o}\t{r['twice'].sum() / 2:g}\t{r['chi']}{ph}"
        f"\t{r['pieces']}\t{r['pinched']}\t{r['boundary_edges']}\t{r['negative_weights']}\t{r['lambdas'][0]:.3e}"
        f"\t{r['residual']:.1e}\t{time.time() - t0:.1f}s"
    ), r


HEADER = "mesh\tboundary\tfaces\t+1/2\t-1/2\tother\tsingular\tindex sum\tchi\tpieces\tpinched\tboundary edges\tnegative cot\tlambda\tresidual\ttime"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("meshes", nargs="*")
    ap.add_argument("--self-test", action="store_true")
    ap.add_argument("--shared", help="run every *.obj in this folder")
    ap.add_argument("--subdivide", type=int, default=1, help="also run K midpoint subdivisions (default 1)")
    ap.add_argument("--boundary", default="both", choices=["strata", "gc", "both"])
    ap.add_argument("--weights", default="cotan", choices=["cotan", "clamped"],
                    help="cotan (the paper's) or clamped (strata's floor of 1e-3 on the edge weight; diagnosis)")
    args = ap.parse_args()
    if args.self_test:
        sys.exit(0 if self_test() else 1)
    paths = list(args.meshes)
    if args.shared:
        paths += sorted(os.path.join(args.shared, f) for f in os.listdir(args.shared) if f.endswith(".obj"))
    print(HEADER)
    for path in paths:
        V, F = read_obj(path)
        name = os.path.splitext(os.path.basename(path))[0]
        has_boundary = Halfedges(V, F).twin.min() < 0
        conventions = ["strata", "gc"] if (args.boundary == "both" and has_boundary) else (
            ["strata"] if args.boundary == "both" else [args.boundary])
        for level in range(args.subdivide + 1):
            for b in conventions:
                line, _ = report(f"{name}{' x' + str(level) if level else ''}", V, F, b, args.weights)
                print(line, flush=True)
            V, F = midpoint_subdivide(V, F)


if __name__ == "__main__":
    main()
