#!/usr/bin/python3
"""Elastic-ball reference with gmsh + CalculiX: meshes, decks, runs, post-processing.

Usage: reference.py [--only MATERIAL/MESH/CASE/THEORY glob] [--skip GLOB] [--reuse]
Writes ball_reference.csv next to this file; scratch files go to ./work/.
See README.md for what each case models.
"""
import argparse
import csv
import fnmatch
import math
import os
import subprocess
import sys
import time

import numpy as np

import deck
from deck import R, TIP_R, Step

HERE = os.path.dirname(os.path.abspath(__file__))
WORK = os.path.join(HERE, 'work')
GEO = os.path.join(HERE, 'ball.geo')
G = 9.81
SEG = 180.0     # CalculiX prints axisymmetric totals for its 2-degree segment

MATERIALS = {
    'foam': dict(E=6000.0, nu=0.3, rho=2.0 / (4.0 / 3.0 * math.pi * R ** 3)),
    'silicone': dict(E=50000.0, nu=0.45, rho=1100.0),
}
# element size h = min(hp + 0.5 d, h0 + grow d, hc + 0.25 dc, hmax) (d: distance
# to the nearer pole, dc: to the centre); fine is coarse with every size halved.  tip = (first arc
# segment at the tip's pole, largest arc segment) of the rigid tip.
MESHES = {
    'coarse': dict(hp=0.0001, h0=0.001, grow=0.12, hc=0.002, hmax=0.03, tip=(0.001, 0.006)),
    'fine': dict(hp=0.00005, h0=0.0005, grow=0.06, hc=0.001, hmax=0.015, tip=(0.0005, 0.003)),
}
THEORIES = ('small_strain', 'nlgeom')
FLOOR_TRAVELS_MM = (1, 2, 5, 10, 20)
HELD_TRAVELS_MM = (1, 2, 5, 10)
PENALTY_PER_E = 1.0e5       # contact penalty K = 1e5 * E  [Pa/m]
SIGMA_INF_PER_E = 1.0e-6    # CalculiX's 'tension at large clearance'
CLAMP_MAIN = 0.010          # centre-held case: clamped central sphere radius [m]
CLAMP_ALT = 0.025


def mass(mat):
    return mat['rho'] * 4.0 / 3.0 * math.pi * R ** 3


# --------------------------------------------------------------------------
# analytic references
# --------------------------------------------------------------------------
def hertz_k(mat, r_eff):
    """F = k d^1.5 for a rigid body of curvature radius r_eff on the ball."""
    estar = mat['E'] / (1.0 - mat['nu'] ** 2)
    return 4.0 / 3.0 * estar * math.sqrt(r_eff)


R_TIP_EFF = 1.0 / (1.0 / TIP_R + 1.0 / R)


def hertz_series_force(mat, travel, preload=0.0):
    """Tip force for a tip travel = tip indentation + extra floor indentation,
    the floor carrying preload + F (Hertz on both poles, in series)."""
    kt, kf = hertz_k(mat, R_TIP_EFF), hertz_k(mat, R)

    def approach(f):
        return (f / kt) ** (2.0 / 3.0) + ((f + preload) / kf) ** (2.0 / 3.0) - (preload / kf) ** (2.0 / 3.0)

    lo, hi = 0.0, 1.0
    while approach(hi) < travel:
        hi *= 2.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if approach(mid) < travel:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def lamb_frequency(mat, eta):
    ct = math.sqrt(mat['E'] / (2.0 * mat['rho'] * (1.0 + mat['nu'])))
    return eta * ct / (2.0 * math.pi * R)


LAMB_ETA_NU03 = {'T2': 2.5011, 'S2': 2.646, 'S0': 4.996}


# --------------------------------------------------------------------------
# running
# --------------------------------------------------------------------------
def sh(cmd, cwd, log):
    with open(log, 'w') as f:
        return subprocess.run(cmd, cwd=cwd, stdout=f, stderr=subprocess.STDOUT,
                              env=dict(os.environ, OMP_NUM_THREADS='1',
                                       CCX_NPROC_EQUATION_SOLVER='1',
                                       CCX_NPROC_STIFFNESS='1')).returncode


def make_mesh(name, dim=2):
    os.makedirs(WORK, exist_ok=True)
    out = os.path.join(WORK, name + '.msh')
    if os.path.exists(out):
        return out
    m = MESHES[name]
    cmd = ['gmsh', '-2', GEO, '-format', 'msh22', '-o', out,
           '-setnumber', 'hp', repr(m['hp']), '-setnumber', 'hc', repr(m['hc']), '-setnumber', 'h0', repr(m['h0']), '-setnumber', 'grow', repr(m['grow']),
           '-setnumber', 'hmax', repr(m['hmax'])]
    if sh(cmd, WORK, os.path.join(WORK, name + '.gmsh.log')) != 0:
        sys.exit('gmsh failed for ' + name)
    return out


RUNLOG = []
MISSING = []


def run_job(job, reuse):
    """Run ccx on WORK/job.inp; returns the parsed .dat.  With reuse, a finished
    job whose deck is unchanged is not rerun."""
    inp = os.path.join(WORK, job + '.inp')
    dat = os.path.join(WORK, job + '.dat')
    stamp = os.path.join(WORK, job + '.done')
    if reuse and os.path.exists(stamp) and os.path.getmtime(stamp) >= os.path.getmtime(inp):
        with open(stamp) as f:
            p = f.read().split(None, 1)
        RUNLOG.append((job, float(p[0]), 'reused, ' + p[1].strip()))
        return deck.read_dat(dat)
    t0 = time.time()
    sh(['ccx', '-i', job], WORK, os.path.join(WORK, job + '.log'))
    secs = time.time() - t0
    with open(os.path.join(WORK, job + '.log')) as f:
        log = f.read()
    ok = 'Job finished' in log and '*ERROR' not in log
    status = 'ok' if ok else 'FAILED: ' + ' '.join(
        l.strip() for l in log.splitlines() if '*ERROR' in l)[:120]
    with open(stamp, 'w') as f:
        f.write('%.1f %s\n' % (secs, status))
    RUNLOG.append((job, secs, status))
    print('  %-40s %6.0f s %s' % (job, secs, status), flush=True)
    # a failed run still returns what it printed before it stopped
    return deck.read_dat(dat) if os.path.exists(dat) else None


ADJUST_RADIUS = 0.001   # floor pair: slave nodes within this radius start on the floor


def floor_adjust(ball):
    """ADJUST distance of the floor contact pair: the initial clearance of the
    ball surface at r = ADJUST_RADIUS, so that the slave nodes with r <= 1 mm
    are moved onto the floor at the start (by at most 2 um) and carry contact
    springs from the first iteration.  Without this the ball resting on the
    floor under gravity has (almost) no support in the first iteration, and
    NLGEOM's first increment diverges (the pole face is not a slave face)."""
    return (ADJUST_RADIUS ** 2 / (2.0 * R)) * 1.0001


def write_and_run(job, ball, mat, steps, reuse, **kw):
    inp = os.path.join(WORK, job + '.inp')
    tmp = inp + '.new'
    kw.setdefault('axis_gap', 0.5 * min(ball.nodes[n][0] for n in ball.bottom_nodes))
    deck.write_deck(tmp, ball, mat, steps, penalty=PENALTY_PER_E * mat['E'],
                    sigma_inf=SIGMA_INF_PER_E * mat['E'], floor_adjust=floor_adjust(ball), **kw)
    if os.path.exists(inp) and open(inp).read() == open(tmp).read():
        os.remove(tmp)      # unchanged deck: keep its time stamp (reuse)
    else:
        os.replace(tmp, inp)
    return run_job(job, reuse)


# --------------------------------------------------------------------------
# post-processing helpers
# --------------------------------------------------------------------------
def series(dat, kind, setname):
    return dat.get((kind, setname), [])


def total_fy(dat, setname):
    """[(total time, axial force of the set for the full 360 degrees, real units)]"""
    return [(t, v[1] * SEG / deck.STRESS_SCALE) for t, v in series(dat, 'total', setname)]


def at_time(seq, t, tol=1e-6):
    for tt, v in seq:
        if abs(tt - t) < tol:
            return v
    raise KeyError('no output at time %g (have %s)' % (t, [tt for tt, _ in seq]))


def deformed(ball, disp):
    """{node: (x, y) deformed} for the nodes in disp"""
    return {n: (ball.nodes[n][0] + u[0], ball.nodes[n][1] + u[1]) for n, u in disp.items()}


def floor_contact(ball, disp, floor_y, adjust):
    """Contact radius and the largest penetration of the bottom surface into the floor.

    Nodes are taken along the arc from the pole; a node is in contact where its
    deformed height is below the floor.  The contact edge is placed between the
    last node in contact and the first open one with a Hertz-like gap
    g ~ (r - a)^1.5 fitted to the first two open nodes (clamped to the bracket).
    The pole node (left out of the contact surface) is ignored.  Nodes that
    CalculiX moved onto the floor at the start (ADJUST) start from height 0.
    """
    pts = []
    for n, u in disp.items():
        x0, y0 = ball.nodes[n]
        if x0 <= 1e-12:
            continue
        if y0 <= adjust:
            y0 = 0.0
        pts.append((x0, x0 + u[0], y0 + u[1] - floor_y))
    pts.sort()
    return _edge(pts)


def _edge(pts):
    """pts: (original r, deformed r, gap) sorted by original r."""
    pen = max([0.0] + [-g for _, _, g in pts])
    last = None
    for i, (_, r, g) in enumerate(pts):
        if g <= 0.0:
            last = i
    if last is None:
        return 0.0, pen, (0.0, pts[0][1])
    if last + 2 >= len(pts):
        return float('nan'), pen, None
    r0 = pts[last][1]
    r1, g1 = pts[last + 1][1], pts[last + 1][2]
    r2, g2 = pts[last + 2][1], pts[last + 2][2]
    q = (g1 / g2) ** (2.0 / 3.0)
    a = (r1 - q * r2) / (1.0 - q)
    a = min(max(a, r0), r1)
    return a, pen, (r0, r1)


def tip_contact(ball, disp, tip_centre_y):
    pts = []
    for n, (x, y) in deformed(ball, disp).items():
        if ball.nodes[n][0] > 1e-12:
            pts.append((ball.nodes[n][0], x, math.hypot(x, y - tip_centre_y) - TIP_R))
    return _edge(sorted(pts))


class Rows:
    def __init__(self):
        self.rows = []

    def add(self, material, case, quantity, travel, value, unit, theory, mesh, notes=''):
        self.rows.append([material, case, quantity, '' if travel is None else '%g' % travel,
                          '%.6g' % value, unit, theory, mesh, notes])


# --------------------------------------------------------------------------
# the cases
# --------------------------------------------------------------------------
def inc_sag(theory):
    return (0.02, 1e-6, 0.2) if theory == 'small_strain' else (0.001, 1e-5, 0.2)


def inc_tip(theory):
    return (0.02, 1e-6, 0.25) if theory == 'small_strain' else (0.005, 1e-4, 0.05)


def case_sag(rows, matname, meshname, theory, ball, reuse):
    mat = MATERIALS[matname]
    job = '%s_%s_%s_sag' % (matname, meshname, theory)
    dat = write_and_run(job, ball, mat, [Step(gravity=True, inc=inc_sag(theory))], reuse,
                        floor=True, nlgeom=(theory == 'nlgeom'))
    if dat is None:
        return None
    t_end = 1.0
    try:
        k = at_time(series(dat, 'displacements', 'KEYN'), t_end)
    except KeyError:
        MISSING.append('%s sag_floor %s %s (run stopped before full gravity)'
                       % (matname, theory, meshname))
        return None
    top, centre = -k[ball.top][1], -k[ball.centre][1]
    react = at_time(total_fy(dat, 'FLOORN'), t_end)
    a, pen, br = floor_contact(ball, at_time(series(dat, 'displacements', 'SBOTN'), t_end), 0.0,
                               floor_adjust(ball))
    w = mass(mat) * G
    c, m = 'sag_floor', meshname
    rows.add(matname, c, 'top_descent', None, top, 'm', theory, m,
             'descent of the top point (initially z=2R)')
    rows.add(matname, c, 'centre_descent', None, centre, 'm', theory, m,
             'descent of the centre point (initially z=R)')
    rows.add(matname, c, 'contact_radius', None, a, 'm', theory, m,
             'floor contact radius (deformed r); last node in contact %.4f, first open %.4f'
             % br)
    rows.add(matname, c, 'floor_reaction', None, react, 'N', theory, m,
             'sum of floor reactions; weight m*g = %.4f N (rel. diff %.1e)'
             % (w, react / w - 1.0))
    rows.add(matname, c, 'max_penetration', None, pen, 'm', theory, m,
             'largest overclosure of a ball node into the floor (penalty K=%.0e*E /m)'
             % PENALTY_PER_E)
    return top


def tip_rows(rows, matname, case, meshname, theory, ball, dat, step_times, travels_mm,
             tip_y0_fn, floor_y, quantity='tip_force', t0=0.0, extra_note=''):
    """tip_y0_fn(travel) -> tip centre height at that travel."""
    tip = total_fy(dat, 'TIPN')
    flo = total_fy(dat, 'FLOORN') if floor_y is not None else None
    worst = 0.0
    for d_mm, ts in zip(travels_mm, step_times):
        t = t0 + ts
        try:
            f_tip = -at_time(tip, t)
        except KeyError:
            MISSING.append('%s %s %s %s travel %g mm (run stopped before)'
                           % (matname, case, theory, meshname, d_mm))
            continue
        note = extra_note
        if flo is not None:
            note += '; floor reaction %.6g N' % at_time(flo, t)
        a, pen, _ = tip_contact(ball, at_time(series(dat, 'displacements', 'STOPN'), t),
                                tip_y0_fn(d_mm * 1e-3))
        worst = max(worst, pen / (d_mm * 1e-3))
        note += '; tip contact radius %.4f m; max tip penetration %.2e m' % (a, pen)
        rows.add(matname, case, quantity, d_mm, f_tip, 'N', theory, meshname, note.lstrip('; '))
    return worst


def case_tip_nogravity(rows, matname, meshname, theory, ball, reuse):
    """Ball just touching the floor, tip just touching its top, no gravity.

    Step 1 holds the centre node and brings tip and floor in by a0 and b0 (their
    Hertz ratio at equal force; a0+b0 = 0.5 mm) so both contacts carry load;
    step 2 frees the centre (the ball is then held by the two contacts only) and
    drives the tip on.  Travel = tip displacement + floor displacement (the
    approach of tip and floor), which is the tip travel from first touch of a
    fixed floor.  The solution of the frictionless elastic problem does not
    depend on this path.
    """
    mat = MATERIALS[matname]
    kt, kf = hertz_k(mat, R_TIP_EFF), hertz_k(mat, R)
    ratio = (kt / kf) ** (2.0 / 3.0)        # floor / tip indentation at equal force
    pre = 0.0005
    a0 = pre / (1.0 + ratio)
    b0 = pre - a0
    dmax = max(FLOOR_TRAVELS_MM) * 1e-3
    tps = [(d * 1e-3 - pre) / (dmax - pre) for d in FLOOR_TRAVELS_MM]
    steps = [Step(tip_uy=-a0, floor_uy=b0, hold='node', inc=(0.5, 1e-6, 0.5)),
             Step(tip_uy=-(dmax - b0), floor_uy=b0, inc=inc_tip(theory), time_points=tps)]
    job = '%s_%s_%s_tipfloor' % (matname, meshname, theory)
    dat = write_and_run(job, ball, mat, steps, reuse, floor=True, tip_z=2 * R,
                        tip_h=MESHES[meshname]['tip'], nlgeom=(theory == 'nlgeom'))
    if dat is None:
        return None
    return tip_rows(rows, matname, 'tip_floor_nogravity', meshname, theory, ball, dat, tps,
                    FLOOR_TRAVELS_MM, lambda d: 2 * R + TIP_R - (d - b0), b0, t0=1.0)


def case_tip_gravity(rows, matname, meshname, theory, ball, top_descent, reuse):
    """Step 1: the ball sags on the floor under gravity while the tip (touching
    the undeformed top at the start) is lowered linearly by the top descent of
    the sag case; the top descends faster than linearly (the sag grows like
    load^(2/3)), so the tip trails it without touching and meets it at the end.
    Step 2: the tip moves down by the travel."""
    mat = MATERIALS[matname]
    dmax = max(FLOOR_TRAVELS_MM) * 1e-3
    tps = [d * 1e-3 / dmax for d in FLOOR_TRAVELS_MM]
    z_tip = 2 * R - top_descent
    steps = [Step(gravity=True, tip_uy=-top_descent, inc=inc_sag(theory)),
             Step(gravity=True, tip_uy=-top_descent - dmax, inc=inc_tip(theory), time_points=tps)]
    job = '%s_%s_%s_tipgrav' % (matname, meshname, theory)
    dat = write_and_run(job, ball, mat, steps, reuse, floor=True, tip_z=2 * R,
                        tip_h=MESHES[meshname]['tip'], nlgeom=(theory == 'nlgeom'))
    if dat is None:
        return None
    w = mass(mat) * G
    # the top point at the end of step 1 must sit at the tip (same sag as the sag case)
    k1 = at_time(series(dat, 'displacements', 'KEYN'), 1.0)
    gap0 = (2 * R + k1[ball.top][1]) - z_tip
    return tip_rows(rows, matname, 'tip_floor_gravity', meshname, theory, ball, dat, tps,
                    FLOOR_TRAVELS_MM, lambda d: z_tip + TIP_R - d, 0.0, t0=1.0,
                    extra_note='weight %.4f N excluded; top-to-tip gap after sag %.1e m'
                    % (w, gap0))


def case_held(rows, matname, meshname, theory, ball, hold, quantity, reuse):
    mat = MATERIALS[matname]
    dmax = max(HELD_TRAVELS_MM) * 1e-3
    tps = [d * 1e-3 / dmax for d in HELD_TRAVELS_MM]
    tag = 'node' if hold == 'node' else 'clamp%d' % round(hold * 1000)
    steps = [Step(tip_uy=-dmax, hold=hold, inc=inc_tip(theory), time_points=tps)]
    job = '%s_%s_%s_held_%s' % (matname, meshname, theory, tag)
    dat = write_and_run(job, ball, mat, steps, reuse, tip_z=2 * R,
                        tip_h=MESHES[meshname]['tip'], nlgeom=(theory == 'nlgeom'))
    if dat is None:
        return None
    if hold == 'node':
        note = 'centre node pinned axially (a point constraint: mesh dependent, not converged)'
    else:
        note = 'central sphere of radius %g m clamped (u=0)' % hold
    return tip_rows(rows, matname, 'tip_centre_held', meshname, theory, ball, dat, tps,
                    HELD_TRAVELS_MM, lambda d: 2 * R + TIP_R - d, None, quantity=quantity,
                    extra_note=note)


MODAL_MESHES = {'coarse': 0.05, 'fine': 0.03}     # C3D10 edge length [m]
MODAL_NEV = 50
CLUSTER_TOL = 0.003     # modes closer than 0.3 % form one (split) multiplet


def case_modal(rows, matname, meshname, reuse):
    """Free-free ball (no floor, no gravity), C3D10, lowest MODAL_NEV modes.

    Rigid-body modes (< 1 Hz) are dropped; the rest are grouped into clusters of
    frequencies within CLUSTER_TOL; a mode's radial fraction sum((u.r)^2)/sum(|u|^2)
    separates torsional modes (~0) from spheroidal ones.
    """
    mat = MATERIALS[matname]
    h = MODAL_MESHES[meshname]
    msh = os.path.join(WORK, 'ball3d_%s.msh' % meshname)
    if not os.path.exists(msh):
        if sh(['gmsh', '-3', os.path.join(HERE, 'ball3d.geo'), '-format', 'msh22', '-o', msh,
               '-setnumber', 'h', repr(h)], WORK, msh + '.log') != 0:
            sys.exit('gmsh failed (3-D ball)')
    nodes, tets = deck.read_msh22_tet10(msh)
    job = '%s_%s_modal' % (matname, meshname)
    inp = os.path.join(WORK, job + '.inp')
    deck.write_modal_deck(inp + '.new', nodes, tets, mat, MODAL_NEV)
    if os.path.exists(inp) and open(inp).read() == open(inp + '.new').read():
        os.remove(inp + '.new')
    else:
        os.replace(inp + '.new', inp)
    if run_job(job, reuse) is None:
        return
    freqs = deck.read_eigen_dat(os.path.join(WORK, job + '.dat'))
    coords, modes = deck.read_frd_modes(os.path.join(WORK, job + '.frd'))
    info = []
    for (mode, f), u in zip(freqs, modes):
        num = den = 0.0
        for n, v in u.items():
            x = coords[n]
            rr = np.linalg.norm(x)
            if rr < 1e-9:
                continue
            num += np.dot(v, x / rr) ** 2
            den += np.dot(v, v)
        info.append((f, num / den))
    elastic = [(f, rf) for f, rf in info if f > 1.0]
    n_rigid = len(info) - len(elastic)
    clusters = []
    for f, rf in elastic:
        if clusters and f / clusters[-1][-1][0] - 1.0 < CLUSTER_TOL:
            clusters[-1].append((f, rf))
        else:
            clusters.append([(f, rf)])
    found = {}
    for cl in clusters[:-1]:        # the last cluster may be cut by MODAL_NEV
        torsional = max(rf for _, rf in cl) < 0.02
        n = len(cl)
        name = None
        if torsional and n == 5 and 'T2' not in found:
            name = 'T2'
        elif not torsional and n == 5 and 'S2' not in found:
            name = 'S2'
        elif not torsional and n == 1 and 'S0' not in found:
            name = 'S0'
        if name:
            found[name] = cl
    summary = '; '.join('%.3f Hz x%d (%s)' % (np.mean([f for f, _ in cl]), len(cl),
                                              'T' if max(rf for _, rf in cl) < 0.02 else 'S')
                        for cl in clusters[:-1])
    for name in ('T2', 'S2', 'S0'):
        if name not in found:
            print('  modal %s %s: %s not identified' % (matname, meshname, name))
            continue
        cl = found[name]
        fs = [f for f, _ in cl]
        rows.add(matname, 'modal', name, None, float(np.mean(fs)), 'Hz', 'small_strain', meshname,
                 'C3D10 h=%g m, %d nodes; mean of %d modes (spread %.2f %%), radial fraction %.3f; '
                 '%d rigid modes < 1 Hz; lowest clusters: %s'
                 % (h, len(nodes), len(fs), 100.0 * (max(fs) - min(fs)) / min(fs),
                    max(rf for _, rf in cl), n_rigid, summary))
        rows.add(matname, 'modal', name + '_multiplicity', None, len(fs), 'count', 'small_strain',
                 meshname, 'modes within %g %% of their neighbour' % (100 * CLUSTER_TOL))


# --------------------------------------------------------------------------
def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--only', default='*', help='glob on material/mesh/case/theory')
    ap.add_argument('--reuse', action='store_true', help='do not rerun finished, unchanged decks')
    ap.add_argument('--skip', default='', help='glob on material/mesh/case/theory not to run')
    ap.add_argument('--csv', default=os.path.join(HERE, 'ball_reference.csv'))
    args = ap.parse_args()
    os.makedirs(WORK, exist_ok=True)
    rows = Rows()
    worst_pen = {}
    t_start = time.time()

    def want(*parts):
        key = '/'.join(parts)
        return fnmatch.fnmatch(key, args.only) and not (args.skip and fnmatch.fnmatch(key, args.skip))

    for meshname in MESHES:
        msh = make_mesh(meshname)
        ball = deck.BallMesh(msh)
        print('mesh %s: %d nodes, %d CAX6 elements' % (meshname, len(ball.nodes), len(ball.tris)),
              flush=True)
        for matname in MATERIALS:
            for theory in THEORIES:
                top = None
                if want(matname, meshname, 'sag', theory) or want(matname, meshname, 'tipgrav', theory):
                    top = case_sag(rows, matname, meshname, theory, ball, args.reuse)
                if want(matname, meshname, 'tipfloor', theory):
                    worst_pen[(matname, meshname, theory, 'tipfloor')] = case_tip_nogravity(
                        rows, matname, meshname, theory, ball, args.reuse)
                if want(matname, meshname, 'tipgrav', theory) and top is not None:
                    worst_pen[(matname, meshname, theory, 'tipgrav')] = case_tip_gravity(
                        rows, matname, meshname, theory, ball, top, args.reuse)
                if want(matname, meshname, 'held', theory):
                    worst_pen[(matname, meshname, theory, 'held')] = case_held(
                        rows, matname, meshname, theory, ball, CLAMP_MAIN, 'tip_force', args.reuse)
                    case_held(rows, matname, meshname, theory, ball, CLAMP_ALT,
                              'tip_force_clamp25mm', args.reuse)
                    if theory == 'small_strain':
                        case_held(rows, matname, meshname, theory, ball, 'node',
                                  'tip_force_node_pin', args.reuse)

    for meshname in MODAL_MESHES:
        if want('foam', meshname, 'modal', 'small_strain'):
            case_modal(rows, 'foam', meshname, args.reuse)

    # analytic rows
    for matname, mat in MATERIALS.items():
        for d in FLOOR_TRAVELS_MM:
            rows.add(matname, 'tip_floor_nogravity', 'tip_force', d,
                     hertz_series_force(mat, d * 1e-3), 'N', 'hertz', 'analytic',
                     'tip-ball (R_eff=%.5f m) and ball-floor (R_eff=R) Hertz contacts in series'
                     % R_TIP_EFF)
        w = mass(mat) * G
        for d in FLOOR_TRAVELS_MM:
            rows.add(matname, 'tip_floor_gravity', 'tip_force', d,
                     hertz_series_force(mat, d * 1e-3, preload=w), 'N', 'hertz', 'analytic',
                     'as tip_floor_nogravity with the floor contact preloaded by the weight %.4f N' % w)
        for d in HELD_TRAVELS_MM:
            rows.add(matname, 'tip_centre_held', 'tip_force', d,
                     (d * 1e-3) ** 1.5 * hertz_k(mat, R_TIP_EFF), 'N', 'hertz', 'analytic',
                     'single tip-ball Hertz contact (travel = indentation)')
        rows.add(matname, 'sag_floor', 'floor_reaction', None, w, 'N', 'exact', 'analytic',
                 'weight m*g, m = %.6g kg' % mass(mat))
    mat = MATERIALS['foam']
    for name, eta in LAMB_ETA_NU03.items():
        rows.add('foam', 'modal', name, None, lamb_frequency(mat, eta), 'Hz', 'lamb', 'analytic',
                 'f = eta c_T/(2 pi R), eta = %g (nu = 0.3), c_T = %.4f m/s'
                 % (eta, math.sqrt(mat['E'] / (2 * mat['rho'] * (1 + mat['nu'])))))

    with open(args.csv, 'w', newline='') as f:
        wr = csv.writer(f, lineterminator='\n')
        wr.writerow(['material', 'case', 'quantity', 'travel_mm', 'value', 'unit', 'theory',
                     'mesh', 'notes'])
        for r in rows.rows:
            wr.writerow(r)
    print('wrote %s (%d rows) in %.0f s' % (args.csv, len(rows.rows), time.time() - t_start))
    print('worst tip penetration / travel:', {k: v for k, v in worst_pen.items()})
    for m in MISSING:
        print('  missing:', m)
    for job, secs, st in RUNLOG:
        print('  run %-40s %7.1f s %s' % (job, secs, st))


if __name__ == '__main__':
    main()
