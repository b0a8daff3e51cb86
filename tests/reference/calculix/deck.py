"""Mesh reading and CalculiX input-deck writing for the elastic-ball reference.

Axisymmetric model in the CalculiX convention: x = radius r, y = axial
coordinate z (the axis of revolution is the y axis).  The ball (radius R,
centre on the axis at y = R) is a gmsh mesh of 6-node triangles (CAX6).  The
rigid tip and the rigid floor are small structured CAX8 meshes whose nodes are
all displacement-prescribed, so they act as rigid master surfaces.
"""
import math

import numpy as np

R = 0.25            # ball radius [m]
TIP_R = 0.05        # tip radius [m]

# node/element number offsets of the tip and floor (set from the ball mesh size,
# kept small: CalculiX sizes its work arrays by the highest node number)
TIP_NODE0 = None
FLOOR_NODE0 = None


# --------------------------------------------------------------------------
# gmsh MSH 2.2 reader (ASCII)
# --------------------------------------------------------------------------
def read_msh22(path):
    nodes = {}
    tris = []
    with open(path) as f:
        lines = iter(f.read().splitlines())
    for line in lines:
        if line.strip() == '$Nodes':
            n = int(next(lines))
            for _ in range(n):
                p = next(lines).split()
                nodes[int(p[0])] = (float(p[1]), float(p[2]))
        elif line.strip() == '$Elements':
            n = int(next(lines))
            for _ in range(n):
                p = [int(v) for v in next(lines).split()]
                etype, ntags = p[1], p[2]
                if etype == 9:      # 6-node second-order triangle
                    tris.append(p[3 + ntags:3 + ntags + 6])
    return nodes, tris


def _area2(a, b, c):
    return (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])


class BallMesh:
    """The ball's CAX6 mesh plus the sets the decks need."""

    def __init__(self, msh_path, bottom_y=0.12, top_y=0.42):
        nodes, tris = read_msh22(msh_path)
        # CalculiX wants counter-clockwise corner order in the (r, z) plane
        fixed = []
        for t in tris:
            a, b, c = (nodes[t[0]], nodes[t[1]], nodes[t[2]])
            if _area2(a, b, c) < 0.0:
                # swap corners 2,3; midside 1-2 <-> 3-1, 2-3 stays
                t = [t[0], t[2], t[1], t[5], t[4], t[3]]
            fixed.append(t)
        self.nodes = nodes
        self.tris = fixed
        # boundary edges: (corner a, corner b, mid) occurring in one element
        edge_count = {}
        for ei, t in enumerate(self.tris):
            for face, (i, j, m) in enumerate(((0, 1, 3), (1, 2, 4), (2, 0, 5))):
                key = tuple(sorted((t[i], t[j])))
                edge_count.setdefault(key, []).append((ei, face, t[m]))
        self.bottom_faces, self.top_faces = [], []
        self.bottom_nodes, self.top_nodes = set(), set()
        for key, owners in edge_count.items():
            if len(owners) != 1:
                continue
            ei, face, mid = owners[0]
            xm, ym = nodes[mid]
            if xm < 1e-12:
                continue      # an edge on the axis
            if min(nodes[key[0]][0], nodes[key[1]][0]) < 1e-12:
                # the face touching the axis is left out of the contact
                # surfaces: CalculiX's node-to-surface spring on the pole node
                # (zero tributary area after the axisymmetric expansion) leaves
                # a residual that never converges.  The face spans r < h0.
                continue
            if abs(math.hypot(xm, ym - R) - R) > 1e-6:
                continue
            if ym < bottom_y:
                self.bottom_faces.append((ei + 1, face + 1))
                self.bottom_nodes.update((key[0], key[1], mid))
            elif ym > top_y:
                self.top_faces.append((ei + 1, face + 1))
                self.top_nodes.update((key[0], key[1], mid))
        self.axis = sorted(k for k, (x, y) in nodes.items() if abs(x) < 1e-12)
        self.centre = self._node_at(0.0, R)
        self.top = self._node_at(0.0, 2 * R)
        self.bottom = self._node_at(0.0, 0.0)

    def _node_at(self, x, y):
        best = min(self.nodes, key=lambda k: (self.nodes[k][0] - x) ** 2
                   + (self.nodes[k][1] - y) ** 2)
        assert math.hypot(self.nodes[best][0] - x, self.nodes[best][1] - y) < 1e-9
        return best

    def n_elements(self):
        return len(self.tris)


# --------------------------------------------------------------------------
# structured CAX8 meshes of the rigid bodies
# --------------------------------------------------------------------------
def _quad8_block(coords_fn, ni, nj, node0):
    """Structured 8-node quads on a (2ni+1) x (2nj+1) node lattice.

    coords_fn(i2, j2) gives (x, y) for lattice indices i2 in 0..2ni, j2 in 0..2nj.
    Returns nodes {id: (x, y)}, elements [[8 ids]] (ccw), lattice id function.
    """
    nodes = {}

    def nid(i2, j2):
        return node0 + 1 + i2 * (2 * nj + 1) + j2

    for i2 in range(2 * ni + 1):
        for j2 in range(2 * nj + 1):
            if i2 % 2 == 1 and j2 % 2 == 1:
                continue      # no centre node in an 8-node quad
            nodes[nid(i2, j2)] = coords_fn(i2, j2)
    elems = []
    for i in range(ni):
        for j in range(nj):
            a, b, c, d = (2 * i, 2 * j), (2 * i + 2, 2 * j), (2 * i + 2, 2 * j + 2), (2 * i, 2 * j + 2)
            corners = [a, b, c, d]
            mids = [(2 * i + 1, 2 * j), (2 * i + 2, 2 * j + 1), (2 * i + 1, 2 * j + 2), (2 * i, 2 * j + 1)]
            e = [nid(*p) for p in corners] + [nid(*p) for p in mids]
            pa, pb, pc = nodes[e[0]], nodes[e[1]], nodes[e[2]]
            if _area2(pa, pb, pc) < 0.0:      # reverse orientation: 1 4 3 2 / 8 7 6 5
                e = [e[0], e[3], e[2], e[1], e[7], e[6], e[5], e[4]]
            elems.append(e)
    return nodes, elems


def _faces_on(nodes, elems, pred):
    """Element faces (1-based elem index within the list, face no.) whose three nodes satisfy pred."""
    out = []
    fdef = ((0, 1, 4), (1, 2, 5), (2, 3, 6), (3, 0, 7))
    for ei, e in enumerate(elems):
        for fi, (a, b, m) in enumerate(fdef):
            if all(pred(nodes[e[k]]) for k in (a, b, m)):
                out.append((ei, fi + 1))
    return out


def graded_stations(total, h0, ratio, hmax):
    """Stations 0..total with first spacing h0, growing by ratio up to hmax."""
    s = [0.0]
    h = h0
    while s[-1] + h < total:
        s.append(s[-1] + h)
        h = min(h * ratio, hmax)
    if total - s[-1] < 0.3 * h and len(s) > 1:
        s[-1] = total
    else:
        s.append(total)
    return s


def _lattice(st):
    """corner stations -> lattice positions (corners and midsides)"""
    out = []
    for k in range(len(st) - 1):
        out += [st[k], 0.5 * (st[k] + st[k + 1])]
    out.append(st[-1])
    return out


def _off_axis(p):
    return p[0] > 1e-12


# The rigid bodies' first element at the axis spans only axis_gap (half the
# ball's pole element) and is not part of the master surface: after
# CalculiX's axisymmetric expansion its face is degenerate at r = 0, and slave
# nodes projected close to it gave a singular system.  The ball's pole face is
# not a slave face either (see BallMesh), so nothing looks for it.

def tip_mesh(z_lowest, axis_gap, h0, hmax, phi_max_deg=75.0, thickness=0.004):
    """A rigid spherical cap: one layer of CAX8 between radius TIP_R-thickness and TIP_R.

    z_lowest: axial position of the tip's lowest point (its pole).
    """
    zc = z_lowest + TIP_R
    arc = TIP_R * math.radians(phi_max_deg)
    st = [0.0] + [axis_gap + v for v in graded_stations(arc - axis_gap, h0, 1.06, hmax)]
    phis = [v / TIP_R for v in _lattice(st)]
    radii = [TIP_R - thickness, TIP_R - 0.5 * thickness, TIP_R]

    def xy(i2, j2):
        rho, phi = radii[i2], phis[j2]
        return (rho * math.sin(phi), zc - rho * math.cos(phi))

    nodes, elems = _quad8_block(xy, 1, len(st) - 1, TIP_NODE0)

    def master(p):
        return abs(math.hypot(p[0], p[1] - zc) - TIP_R) < 1e-9 and _off_axis(p)

    return nodes, elems, _faces_on(nodes, elems, master)


def floor_mesh(axis_gap, h0, width=0.34, hmax=0.004, thickness=0.01):
    st = [0.0] + [axis_gap + v for v in graded_stations(width - axis_gap, h0, 1.1, hmax)]
    xs = _lattice(st)

    def xy(i2, j2):
        return (xs[j2], -thickness + thickness * i2 / 2.0)

    nodes, elems = _quad8_block(xy, 1, len(st) - 1, FLOOR_NODE0)
    faces = _faces_on(nodes, elems, lambda p: abs(p[1]) < 1e-12 and _off_axis(p))
    return nodes, elems, faces


# --------------------------------------------------------------------------
# deck writer
# --------------------------------------------------------------------------
def _ids_block(ids, per_line=8):
    ids = list(ids)
    return '\n'.join(', '.join(str(i) for i in ids[k:k + per_line])
                     for k in range(0, len(ids), per_line)) + '\n'


class Step:
    """One *STEP.  Displacements are absolute values at the end of the step
    (CalculiX ramps them linearly from the previous step's values).

    gravity: apply GRAV (ramped in the step where it first appears, kept after)
    tip_uy, floor_uy: prescribed axial displacement of the rigid tip / floor
    hold: None, 'node' (centre node uy = 0) or a clamp radius [m] (all nodes
          within it fixed in r and z)
    inc: (initial, minimum, maximum) increment as fractions of the step time
    time_points: step-time fractions at which results are printed (None: every
          increment)
    """

    def __init__(self, gravity=False, tip_uy=0.0, floor_uy=0.0, hold=None,
                 inc=(0.01, 1e-6, 0.05), time_points=None):
        self.gravity, self.tip_uy, self.floor_uy, self.hold = gravity, tip_uy, floor_uy, hold
        self.inc, self.time_points = inc, time_points


# Stress scale of the decks.  In SI units the foam's forces on CalculiX's 2-degree
# axisymmetric segment are ~1e-6 N, below the solver's absolute residual
# thresholds, and Newton fails to judge convergence.  E, density, contact
# penalty and contact tension are all multiplied by STRESS_SCALE (the static
# equilibrium, small-strain or NLGEOM, has exactly the same displacements) and
# the printed forces are divided by it in post-processing.
STRESS_SCALE = 1.0e5


def write_deck(path, ball, mat, steps, *, floor=False, tip_z=None, tip_h=(0.0005, 0.003),
               axis_gap=5e-5,
               nlgeom=False, penalty=None, sigma_inf=None, print_surface=True,
               floor_adjust=None):
    """Write one CalculiX deck (see Step).  penalty, sigma_inf and mat are in
    real (unscaled) units."""
    global TIP_NODE0, FLOOR_NODE0
    base = 1000 * (max(ball.nodes) // 1000 + 1)
    TIP_NODE0, FLOOR_NODE0 = base, base + 2000
    E, nu, rho = mat['E'] * STRESS_SCALE, mat['nu'], mat['rho'] * STRESS_SCALE
    out = []
    w = out.append
    w('*HEADING\nElastic ball reference (axisymmetric, x = r, y = z)\n')
    w('*NODE, NSET=NBALL\n')
    for k in sorted(ball.nodes):
        x, y = ball.nodes[k]
        w('%d, %.12e, %.12e\n' % (k, x, y))
    w('*ELEMENT, TYPE=CAX6, ELSET=BALL\n')
    for ei, t in enumerate(ball.tris):
        w('%d, %s\n' % (ei + 1, ', '.join(str(n) for n in t)))
    w('*NSET, NSET=AXIS\n' + _ids_block(ball.axis))
    w('*NSET, NSET=CENTRE\n%d\n' % ball.centre)
    w('*NSET, NSET=KEYN\n%d, %d, %d\n' % (ball.bottom, ball.centre, ball.top))
    clamps = sorted({s.hold for s in steps if isinstance(s.hold, float)})
    for rc in clamps:
        ids = [k for k, (x, y) in ball.nodes.items() if math.hypot(x, y - R) <= rc + 1e-12]
        w('*NSET, NSET=CLAMP%d\n' % round(rc * 1e4) + _ids_block(sorted(ids)))
    w('*SOLID SECTION, ELSET=BALL, MATERIAL=BALLMAT\n')
    w('*MATERIAL, NAME=BALLMAT\n*ELASTIC\n%.9e, %.9e\n*DENSITY\n%.9e\n' % (E, nu, rho))
    w('*MATERIAL, NAME=RIGIDMAT\n*ELASTIC\n%.9e, 0.3\n*DENSITY\n0.\n' % (1000 * E))
    contact_pairs = []
    if floor:
        fn, fe, ff = floor_mesh(axis_gap, tip_h[0])
        w('*NODE, NSET=FLOORN\n')
        for k in sorted(fn):
            w('%d, %.12e, %.12e\n' % (k, fn[k][0], fn[k][1]))
        w('*ELEMENT, TYPE=CAX8, ELSET=FLOOR\n')
        for ei, e in enumerate(fe):
            w('%d, %s\n' % (FLOOR_NODE0 + ei + 1, ', '.join(str(n) for n in e)))
        w('*SOLID SECTION, ELSET=FLOOR, MATERIAL=RIGIDMAT\n')
        w('*SURFACE, NAME=MFLOOR, TYPE=ELEMENT\n')
        for ei, fno in ff:
            w('%d, S%d\n' % (FLOOR_NODE0 + ei + 1, fno))
        w('*SURFACE, NAME=SBOT, TYPE=ELEMENT\n')
        for ei, fno in ball.bottom_faces:
            w('%d, S%d\n' % (ei, fno))
        w('*NSET, NSET=SBOTN\n' + _ids_block(sorted(ball.bottom_nodes)))
        contact_pairs.append(('SBOT', 'MFLOOR', floor_adjust))
    if tip_z is not None:
        tn, te, tf = tip_mesh(tip_z, axis_gap, *tip_h)
        w('*NODE, NSET=TIPN\n')
        for k in sorted(tn):
            w('%d, %.12e, %.12e\n' % (k, tn[k][0], tn[k][1]))
        w('*ELEMENT, TYPE=CAX8, ELSET=TIP\n')
        for ei, e in enumerate(te):
            w('%d, %s\n' % (TIP_NODE0 + ei + 1, ', '.join(str(n) for n in e)))
        w('*SOLID SECTION, ELSET=TIP, MATERIAL=RIGIDMAT\n')
        w('*SURFACE, NAME=MTIP, TYPE=ELEMENT\n')
        for ei, fno in tf:
            w('%d, S%d\n' % (TIP_NODE0 + ei + 1, fno))
        w('*SURFACE, NAME=STOP, TYPE=ELEMENT\n')
        for ei, fno in ball.top_faces:
            w('%d, S%d\n' % (ei, fno))
        w('*NSET, NSET=STOPN\n' + _ids_block(sorted(ball.top_nodes)))
        contact_pairs.append(('STOP', 'MTIP', None))
    if contact_pairs:
        w('*SURFACE INTERACTION, NAME=SI\n')
        w('*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n%.6e, %.6e\n' % (penalty * STRESS_SCALE,
                                                                     sigma_inf * STRESS_SCALE))
        for s, m, adj in contact_pairs:
            w('*CONTACT PAIR, INTERACTION=SI, TYPE=NODE TO SURFACE%s\n%s, %s\n'
              % ('' if adj is None else ', ADJUST=%.3e' % adj, s, m))
    for si, st in enumerate(steps):
        if st.time_points:
            w('*TIME POINTS, NAME=TP%d\n' % (si + 1)
              + _ids_block(['%.9g' % t for t in st.time_points]))

    gravity_on = False
    for si, st in enumerate(steps):
        w('*STEP, NLGEOM, INC=5000\n' if nlgeom else '*STEP, INC=5000\n')
        w('*STATIC\n%g, 1., %g, %g\n' % (st.inc[0], st.inc[1], st.inc[2]))
        w('*BOUNDARY, OP=NEW\nAXIS, 1, 1\n')
        if floor:
            w('FLOORN, 1, 1\nFLOORN, 2, 2, %.12e\n' % st.floor_uy)
        if tip_z is not None:
            w('TIPN, 1, 1\nTIPN, 2, 2, %.12e\n' % st.tip_uy)
        if st.hold == 'node':
            w('CENTRE, 2, 2\n')
        elif st.hold is not None:
            w('CLAMP%d, 1, 2\n' % round(st.hold * 1e4))
        if st.gravity and not gravity_on:
            w('*DLOAD\nBALL, GRAV, %.6f, 0., -1., 0.\n' % 9.81)
            gravity_on = True
        tps = ', TIME POINTS=TP%d' % (si + 1) if st.time_points else ''
        if tip_z is not None:
            w('*NODE PRINT, NSET=TIPN, TOTALS=ONLY%s\nRF\n' % tps)
        if floor:
            w('*NODE PRINT, NSET=FLOORN, TOTALS=ONLY%s\nRF\n' % tps)
        if st.hold == 'node':
            w('*NODE PRINT, NSET=CENTRE, TOTALS=ONLY%s\nRF\n' % tps)
        elif st.hold is not None:
            w('*NODE PRINT, NSET=CLAMP%d, TOTALS=ONLY%s\nRF\n' % (round(st.hold * 1e4), tps))
        w('*NODE PRINT, NSET=KEYN%s\nU\n' % tps)
        if print_surface and floor:
            w('*NODE PRINT, NSET=SBOTN%s\nU\n' % tps)
        if print_surface and tip_z is not None:
            w('*NODE PRINT, NSET=STOPN%s\nU\n' % tps)
        w('*END STEP\n')
    with open(path, 'w') as f:
        f.write(''.join(out))


# --------------------------------------------------------------------------
# .dat reader
# --------------------------------------------------------------------------
def read_dat(path):
    """Returns {(kind, set): [(time, {node: values} or [totals])]} in file order."""
    res = {}
    with open(path) as f:
        lines = f.read().splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if ' for set ' in line and ' and time ' in line:
            head, rest = line.split(' for set ')
            setname, t = rest.split(' and time ')
            kind = head.strip()
            t = float(t)
            i += 1
            while i < len(lines) and not lines[i].strip():
                i += 1
            data = {}
            while i < len(lines) and lines[i].strip():
                p = lines[i].split()
                if kind.startswith('total'):
                    data = [float(v) for v in p]
                else:
                    data[int(p[0])] = [float(v) for v in p[1:]]
                i += 1
            res.setdefault((kind.split()[0] if not kind.startswith('total') else 'total',
                            setname.strip()), []).append((t, data))
        else:
            i += 1
    return res


# --------------------------------------------------------------------------
# 3-D ball (C3D10) for the free-free modal check
# --------------------------------------------------------------------------
def read_msh22_tet10(path):
    nodes, tets = {}, []
    with open(path) as f:
        lines = iter(f.read().splitlines())
    for line in lines:
        if line.strip() == '$Nodes':
            for _ in range(int(next(lines))):
                p = next(lines).split()
                nodes[int(p[0])] = np.array([float(v) for v in p[1:4]])
        elif line.strip() == '$Elements':
            for _ in range(int(next(lines))):
                p = [int(v) for v in next(lines).split()]
                if p[1] == 11:          # 10-node second-order tetrahedron
                    tets.append(p[3 + p[2]:3 + p[2] + 10])
    # CalculiX C3D10: corners 1-4, then midside nodes of edges
    # 1-2, 2-3, 3-1, 1-4, 2-4, 3-4.  Midside nodes are matched by position
    # (independent of gmsh's edge order) and the corner order is made
    # right-handed (positive volume).
    out = []
    for t in tets:
        c = list(t[:4])
        a, b, cc, d = (nodes[k] for k in c)
        if np.dot(np.cross(b - a, cc - a), d - a) < 0.0:
            c[1], c[2] = c[2], c[1]
        mids = {}
        for m in t[4:]:
            mids[m] = nodes[m]
        order = []
        for i, j in ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)):
            target = 0.5 * (nodes[c[i]] + nodes[c[j]])
            best = min(mids, key=lambda m: np.sum((mids[m] - target) ** 2))
            order.append(best)
            del mids[best]
        out.append(c + order)
    return nodes, out


def write_modal_deck(path, nodes, tets, mat, nev):
    out = ['*HEADING\nFree-free ball, C3D10\n*NODE, NSET=NALL\n']
    for k in sorted(nodes):
        out.append('%d, %.12e, %.12e, %.12e\n' % (k, *nodes[k]))
    out.append('*ELEMENT, TYPE=C3D10, ELSET=BALL\n')
    for ei, t in enumerate(tets):
        out.append('%d, %s\n' % (ei + 1, ', '.join(str(n) for n in t)))
    out.append('*MATERIAL, NAME=BALLMAT\n*ELASTIC\n%.9e, %.9e\n*DENSITY\n%.9e\n'
               % (mat['E'], mat['nu'], mat['rho']))
    out.append('*SOLID SECTION, ELSET=BALL, MATERIAL=BALLMAT\n')
    out.append('*STEP\n*FREQUENCY\n%d\n*NODE FILE\nU\n*END STEP\n' % nev)
    with open(path, 'w') as f:
        f.write(''.join(out))


def read_eigen_dat(path):
    """[(mode, frequency in cycles/time)] from the .dat eigenvalue table."""
    res = []
    with open(path) as f:
        lines = f.read().splitlines()
    on = False
    for line in lines:
        if 'E I G E N V A L U E   O U T P U T' in line:
            on = True
            continue
        if on:
            p = line.split()
            if len(p) == 5 and p[0].isdigit():
                res.append((int(p[0]), float(p[3])))
            elif res and not line.strip():
                break
    return res


def read_frd_modes(path):
    """Node coordinates and the DISP block of every mode from a .frd file."""
    coords, modes = {}, []
    with open(path) as f:
        lines = f.read().splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith('    2C'):
            i += 1
            while not lines[i].startswith(' -3'):
                s = lines[i]
                coords[int(s[3:13])] = np.array([float(s[13:25]), float(s[25:37]), float(s[37:49])])
                i += 1
        elif line.startswith(' -4  DISP'):
            i += 1
            while lines[i].startswith(' -5'):
                i += 1
            u = {}
            while not lines[i].startswith(' -3'):
                s = lines[i]
                u[int(s[3:13])] = np.array([float(s[13:25]), float(s[25:37]), float(s[37:49])])
                i += 1
            modes.append(u)
        i += 1
    return coords, modes
