"""The ``Simulation`` object: owns the state arrays, runs K steps at a time inside numba,
calls the rig's callback between chunks, checks the guards, saves/restores checkpoints.

Typical use (SI units)::

    sim = Simulation(thickness=1.0, gravity=(0, -1000.0), damping=0.7)
    ids = sim.add_balls(x, y, r, density=2950.0, stone_id=s, material_id=0)
    bottom = sim.add_wall([(0, 0), (0.5, 0)], segments=10)
    sim.install_flat_joints({0: FlatJointMaterial.hard()})
    sim.run(10000, callback=servo, every=100)
    sim.wall_force(bottom).sum(axis=0)
"""
from dataclasses import fields

import numpy as np

from . import crushing, output
from . import params as P
from .bonds import find_bond_candidates
from .checkpoint import load_state, save_state
from .clumps import buried, mass_properties, pebble_sums
from .control import Control
from .bound import clump_stiffness, springs, stepper, timestep
from .engine import rebuild_lists
from .integrate import reset_forces
from .law import ContactLaw
from .materials import ContactMaterial
from .state import Balls, Bonds, BreakLog, Clumps, Pairs, RunState, SplitLog, WallPairs, Walls
from .submodels import NCOEF, contact_stiffness

_NO_CONTROL = Control.empty()


class SimulationError(RuntimeError):
    """A guard stopped the run (NaN/Inf, runaway velocity, ball outside the domain)."""


class Simulation:
    """2D DEM model in PFC2D conventions (disks of thickness t, forces per thickness t).

    Parameters
    ----------
    thickness : out-of-plane thickness t [m] (PFC2D: 1 m).
    gravity : gravity vector [m/s^2].
    damping : PFC local damping alpha for balls (0.7 = PFC material-genesis default);
        stored per ball, change with ``set_damping``.
    clump_damping : local damping for clumps (default: same as ``damping``).
    dt : fixed timestep [s]; None = automatic, dt = dt_safety * dt_crit recomputed at
        every neighbour rebuild.
    dt_safety : the factor f of the automatic timestep.
    skin : Verlet skin [m]; None = 0.5 * largest radius at the first run.
    domain : (xmin, ymin, xmax, ymax) ball centres must stay inside; None = bounding box
        of balls and walls at the first run, enlarged by half its size on every side.
    law : a ``ContactLaw`` (sub-models, law.py), or "pfc" (= ContactLaw.pfc(): linear +
        dashpots, the engine's law) or "hooke" (= ContactLaw.hooke(): LAMMPS
        gran/hooke/history, for the benchmark; then pass ``hooke=dict(kn, kt, gamma_n,
        gamma_t, mu)`` as the coefficients of every material pair).
    n_elements : flat-joint elements per interface N (thesis N_r = 1).
    vmax : runaway guard [m/s].
    density_scaling : raise inertial masses so that the given ``dt`` is stable
        (quasi-static stages only; report ``inertial_number``).
    """

    def __init__(self, thickness=1.0, gravity=(0.0, -9.81), damping=0.0, clump_damping=None,
                 dt=None, dt_safety=0.8, skin=None, domain=None, law="pfc", hooke=None,
                 n_elements=1, vmax=1.0e3, density_scaling=False):
        self.prm = P.new_params()
        p = self.prm
        p[P.THICK] = thickness
        p[P.GX], p[P.GY] = gravity
        p[P.ALPHA] = damping
        p[P.ALPHA_CLUMP] = damping if clump_damping is None else clump_damping
        p[P.DT_SAFETY] = dt_safety
        p[P.AUTO_DT] = 0.0 if dt is not None else 1.0
        p[P.DT] = dt if dt is not None else 0.0
        p[P.VMAX] = vmax
        p[P.DSCALE] = 1.0 if density_scaling else 0.0
        if density_scaling and dt is None:
            raise ValueError("density_scaling needs a fixed dt")
        if isinstance(law, str):
            if law not in ("pfc", "hooke"):
                raise ValueError(f"law must be 'pfc', 'hooke' or a ContactLaw, got {law!r}")
            law = ContactLaw.pfc() if law == "pfc" else ContactLaw.hooke()
        self.law = law
        self._layout = law.layout()
        self.skin = skin
        self.domain = domain
        self.n_elements = int(n_elements)
        self.balls = Balls()
        self.walls = Walls()
        self.clumps = Clumps()
        self.pairs = Pairs.empty(64, law.width)
        self.wpairs = WallPairs.empty(64, law.width)
        self.bonds = self._empty_bonds()
        self.log = BreakLog()
        self.splits = SplitLog()
        self.cnt = np.array([0, 0, 1], np.int64)      # step, neighbour builds, rebuild flag
        self.eacc = np.zeros(P.NENERGY)
        self.err = np.zeros(2)
        self.coef = np.zeros((1, 1, NCOEF))
        self.set_contact_material(hooke if hooke is not None else ContactMaterial())
        self._prepared = False

    # ------------------------------------------------------------------ building
    def _empty_bonds(self):
        b = Bonds()
        ne = self.n_elements
        b.state = np.zeros((0, ne), np.uint8)
        b.fn = np.zeros((0, ne))
        b.fs = np.zeros((0, ne))
        return b

    def set_contact_material(self, cm, mat_a=None, mat_b=None):
        """Contact-law coefficients for materials (a, b) (symmetric); without ids: for
        every pair of materials. ``cm``: a ContactMaterial or a dict of the law's
        coefficient names (``self.law.coefficients``). Walls use ``Walls.mat`` ids from
        the same table."""
        row = self.law.row(cm.coefficients() if hasattr(cm, "coefficients") else cm)
        if mat_a is None:
            self._default_row = row
            self.coef[:, :] = row
            return
        self._ensure_materials(max(mat_a, mat_b) + 1)
        self.coef[mat_a, mat_b] = row
        self.coef[mat_b, mat_a] = row

    def set_contact_coefficient(self, name, value, mat_a=None, mat_b=None):
        """One coefficient of the law (e.g. "mu") for materials (a, b), or for every pair
        of the materials there are now (materials added later get the default's)."""
        c = self.law.column(name)
        if mat_a is None:
            self.coef[..., c] = value
        else:
            self._ensure_materials(max(mat_a, mat_b) + 1)
            self.coef[mat_a, mat_b, c] = self.coef[mat_b, mat_a, c] = value

    def contact_coefficient(self, name):
        """The material-pair table of one coefficient, (n_materials, n_materials)."""
        return self.coef[..., self.law.column(name)].copy()

    def _ensure_materials(self, n):
        if self.coef.shape[0] < n:
            coef = np.empty((n, n, self.coef.shape[2]))
            coef[:, :] = self._default_row
            k = self.coef.shape[0]
            coef[:k, :k] = self.coef
            self.coef = coef

    def add_balls(self, x, y, r, density, stone_id=-1, material_id=0, vx=0.0, vy=0.0,
                  omega=0.0):
        """Add disks (arrays or scalars); returns their ids. m = rho*pi*R^2*t, I = m R^2/2."""
        x, y, r = (np.atleast_1d(np.asarray(a, float)) for a in (x, y, r))
        k = len(x)
        t = self.prm[P.THICK]
        m = np.broadcast_to(np.asarray(density, float), (k,)) * np.pi * r ** 2 * t
        inertia = 0.5 * m * r ** 2
        mat = np.broadcast_to(np.asarray(material_id), (k,))
        self._ensure_materials(int(mat.max()) + 1 if k else 1)
        ids = self.balls.append(
            pos=np.column_stack([x, y]), vel=np.column_stack(np.broadcast_arrays(vx, vy, x)[:2]),
            omega=omega, rad=r, mass=m, inertia=inertia, minv=1.0 / m, iinv=1.0 / inertia,
            stone=stone_id, mat=mat, fix=0, clump=-1, alive=1, pos0=np.column_stack([x, y]),
            damp=self.prm[P.ALPHA])
        self._touch()
        return ids

    def add_wall(self, points, segments=1, material_id=0, closed=False):
        """Polyline wall through ``points``; each edge split into ``segments`` equal
        segments (so a rig can read forces per segment). Returns the segment ids.
        Every segment rotates about the first point unless ``set_wall_velocity`` says."""
        pts = np.asarray(points, float)
        if closed:
            pts = np.vstack([pts, pts[:1]])
        segs = []
        for a, b in zip(pts[:-1], pts[1:]):
            u = np.linspace(0.0, 1.0, segments + 1)[:, None]
            q = a + u * (b - a)
            segs += [np.r_[q[s], q[s + 1]] for s in range(segments)]
        segs = np.array(segs)
        k0, k = len(self.walls), len(segs)
        link = np.column_stack([np.arange(k0 - 1, k0 + k - 1), np.arange(k0 + 1, k0 + k + 1)])
        if closed:
            link[0, 0], link[-1, 1] = k0 + k - 1, k0
        else:
            link[0, 0], link[-1, 1] = -1, -1
        ids = self.walls.append(seg=segs, centre=np.broadcast_to(pts[0], (len(segs), 2)),
                                mat=material_id, link=link)
        self._ensure_materials(material_id + 1)
        self._touch()
        return ids

    def set_segment_y(self, s, start=None, end=None):
        """Move segment ``s``'s start and/or end point to height ``start`` / ``end`` (x kept):
        a membrane segment following the platens. The neighbour lists are rebuilt."""
        for col, y in ((1, start), (3, end)):
            if y is not None:
                self.walls.seg[s, col] = y
        self._touch()

    def set_wall_velocity(self, ids, vel=(0.0, 0.0), omega=0.0, centre=None):
        """Kinematic motion of segments ``ids``: translation ``vel`` and rotation
        ``omega`` about ``centre`` (a point moving with the wall)."""
        self.walls.vel[ids] = vel
        self.walls.omega[ids] = omega
        if centre is not None:
            self.walls.centre[ids] = centre

    def add_clump(self, x, y, r, density, held=False, material_id=0, stone_id=-1,
                  mass=None, inertia=None, vel=(0.0, 0.0), omega=0.0):
        """Rigid clump of pebbles (x, y, r). Mass properties from pebble sums unless
        ``mass``/``inertia`` are given (see clumps.py). Returns the clump id."""
        x, y, r = (np.atleast_1d(np.asarray(a, float)) for a in (x, y, r))
        m, cx, cy, ii = mass_properties(x, y, r, density, self.prm[P.THICK])
        m = m if mass is None else mass
        ii = ii if inertia is None else inertia
        cid = self.clumps.append(pos=(cx, cy), vel=vel, omega=omega, mass=m, inertia=ii,
                                 held=1 if held else 0, damp=self.prm[P.ALPHA_CLUMP])
        ids = self.add_balls(x, y, r, density, stone_id=stone_id, material_id=material_id)
        self.balls.clump[ids] = cid
        self.balls.offset[ids] = np.column_stack([x - cx, y - cy])
        self.balls.minv[ids] = 1.0 / m        # dashpot effective mass = clump mass
        self._follow_clumps(ids)
        self.balls.pos0[ids] = self.balls.pos[ids]
        return cid

    def _follow_clumps(self, ids):
        """Pebbles ``ids`` placed and moving with their clumps' rigid motion, as the
        kernels' place_pebbles does every step (theta = 0: the offsets as they are)."""
        b, c = self.balls, self.clumps
        k = b.clump[ids]
        cs, sn = np.cos(c.theta[k]), np.sin(c.theta[k])
        ox, oy = b.offset[ids, 0], b.offset[ids, 1]
        rx = cs * ox - sn * oy
        ry = sn * ox + cs * oy
        b.pos[ids] = c.pos[k] + np.column_stack([rx, ry])
        b.vel[ids] = c.vel[k] + c.omega[k][:, None] * np.column_stack([-ry, rx])
        b.omega[ids] = c.omega[k]

    def make_clumps(self, groups):
        """Each group of live free balls (ball ids) becomes one free rigid clump of those
        balls as its pebbles, in place (ids, stones, materials, contacts and their history
        kept): mass properties from pebble sums of the balls' own masses (clumps.py); the
        group's linear and angular momentum kept (v = sum m v / M, omega = L_c / I_c),
        which is the rigid motion of least kinetic energy with that momentum, so none is
        added. Bonds among a group's balls become inactive (a rigid body has no internal
        springs) and stay in the bond arrays as the record of which balls were joined.
        Returns the clump ids."""
        b = self.balls
        ids = []
        for g in groups:
            g = np.asarray(g, np.int64)
            if len(g) == 0 or not (b.alive[g] == 1).all() or (b.clump[g] >= 0).any():
                raise ValueError("make_clumps: every group must be non-empty live free balls")
            mi, x, y = b.mass[g], b.pos[g, 0], b.pos[g, 1]
            m, cx, cy, inertia = pebble_sums(mi, x, y, b.inertia[g])
            d = np.column_stack([x - cx, y - cy])
            v = np.array([(mi * b.vel[g, 0]).sum(), (mi * b.vel[g, 1]).sum()]) / m
            spin = (b.inertia[g] * b.omega[g]
                    + mi * (d[:, 0] * b.vel[g, 1] - d[:, 1] * b.vel[g, 0])).sum()
            cid = self.clumps.append(pos=(cx, cy), vel=v, omega=spin / inertia, mass=m,
                                     inertia=inertia, held=0, damp=float(b.damp[g[0]]))
            b.clump[g] = cid
            b.offset[g] = d
            b.minv[g] = 1.0 / m           # dashpot effective mass = clump mass
            self._follow_clumps(g)        # placed as the kernels will (round-off)
            ids.append(cid)
        bd = self.bonds
        inner = (b.clump[bd.i] >= 0) & (b.clump[bd.i] == b.clump[bd.j])
        bd.active[inner] = 0      # kept in the arrays: which balls were joined
        self._touch()
        return ids

    def bury(self, clumps):
        """Mark the pebbles of ``clumps`` that no body of half the smallest live ball's
        radius can touch from outside their clump (clumps.buried; a body overlapping the
        pebbles of the outline by up to half its radius is covered too) and clear the mark
        of the others: buried pebbles have no contacts to look for, so the kernel skips
        them in its lists and places them only when the state is read. Their clump's mass
        and inertia stay those of every pebble. Returns how many are buried."""
        b = self.balls
        live = b.alive == 1
        probe = 0.5 * float(b.rad[live].min())
        for c in clumps:
            peb = np.flatnonzero((b.clump == c) & live)
            b.buried[peb] = buried(b.pos[peb, 0], b.pos[peb, 1], b.rad[peb], probe) if len(peb) > 1 else 0
            hid = peb[b.buried[peb] == 1]
            b.force[hid] = 0.0
            b.moment[hid] = 0.0
        self._touch()
        return int(b.buried[np.isin(b.clump, clumps)].sum())

    def set_clump_velocity(self, cid, vel=None, omega=None, held=None):
        if vel is not None:
            self.clumps.vel[cid] = vel
        if omega is not None:
            self.clumps.omega[cid] = omega
        if held is not None:
            self.clumps.held[cid] = 1 if held else 0

    def set_ball_velocity(self, ids, vel=None, omega=None, hold=None):
        """Set velocities; ``hold`` = bitmask (1 x, 2 y, 4 spin) of velocity-held dofs."""
        if vel is not None:
            self.balls.vel[ids] = vel
        if omega is not None:
            self.balls.omega[ids] = omega
        if hold is not None:
            self.balls.fix[ids] = hold

    def perturb_velocities(self, sd, seed):
        """Add a normal draw of standard deviation ``sd`` [m/s] to each velocity component
        of every live free ball (none held) and then of every free clump of stone balls
        (rigid stones; not a plate or loading body), its pebbles moved with it: an
        infinitesimal change of the state, to measure how far chaos alone carries a run
        (loop.select)."""
        b, c = self.balls, self.clumps
        rng = np.random.default_rng(seed)
        free = np.flatnonzero((b.alive == 1) & (b.clump < 0) & (b.fix == 0))
        b.vel[free] += rng.normal(0.0, sd, (free.size, 2))
        stone = np.zeros(len(c), bool)
        stone[b.clump[(b.clump >= 0) & (b.stone >= 0) & (b.alive == 1)]] = True
        rigid = np.flatnonzero(stone & (c.held == 0))
        if rigid.size:
            c.vel[rigid] += rng.normal(0.0, sd, (rigid.size, 2))
            self._follow_clumps(np.flatnonzero(np.isin(b.clump, rigid)))

    def apply_force(self, ids, f):
        """Constant external force on balls ``ids`` (pebbles: passed to their clump) until
        changed [N]."""
        self.balls.fext[ids] = f

    def install_flat_joints(self, materials, balls=None):
        """Flat joints between balls of one stone whose gap < g_i (per ``materials``:
        a FlatJointMaterial for all, or {material_id: FlatJointMaterial}, the material
        of ball i). Initial gap g_0 = 0: the current distance is the bonded state.
        Balls of clumps are never bonded. Returns the number of bonds installed.
        Defaults of FlatJointMaterial: thesis Table 4.2 (hard rock)."""
        b = self.balls
        alive = (b.alive & (b.clump < 0)).astype(np.uint8)    # never inside a rigid clump
        if balls is not None:
            mask = np.zeros_like(alive)
            mask[balls] = 1
            alive &= mask
        fjm = materials if isinstance(materials, dict) else None
        gap_factor = min(m.gap_factor for m in (fjm.values() if fjm else [materials]))
        i, j = find_bond_candidates(b.pos, b.rad, b.stone, alive, max(gap_factor, 1e-12))
        mats = [fjm[int(m)] if fjm else materials for m in b.mat[i]]
        if fjm:   # per-material gap factors
            keep = np.array([np.hypot(*(b.pos[jj] - b.pos[ii])) - b.rad[ii] - b.rad[jj]
                             < m.gap_factor * min(b.rad[ii], b.rad[jj])
                             for ii, jj, m in zip(i, j, mats)], bool)
            i, j, mats = i[keep], j[keep], [m for m, k in zip(mats, keep) if k]
        return self._append_bonds(i, j, mats)

    def _append_bonds(self, i, j, mats):
        b, bd, ne = self.balls, self.bonds, self.n_elements
        rmin = np.minimum(b.rad[i], b.rad[j])
        rsum = b.rad[i] + b.rad[j]
        kn = np.array([m.E for m in mats]) / rsum
        new = dict(
            i=i.astype(np.int32), j=j.astype(np.int32), active=np.ones(len(i), np.uint8),
            rbar=np.array([m.lam for m in mats]) * rmin,
            d0=np.hypot(*(b.pos[j] - b.pos[i]).T),
            gi=np.array([m.gap_factor for m in mats]) * rmin,
            kn=kn, ks=kn / np.array([m.kappa for m in mats]),
            sigc=np.array([m.sigma_c for m in mats]), coh=np.array([m.c for m in mats]),
            tanphi=np.tan(np.radians([m.phi_deg for m in mats])),
            mu=np.array([m.mu for m in mats]), theta=np.zeros(len(i)), moment=np.zeros(len(i)),
            state=np.ones((len(i), ne), np.uint8), fn=np.zeros((len(i), ne)),
            fs=np.zeros((len(i), ne)))
        if len(bd):
            # drop pairs already bonded
            have = set(zip(bd.i.tolist(), bd.j.tolist()))
            keep = np.array([(a, c) not in have for a, c in zip(new["i"], new["j"])], bool)
            new = {k: v[keep] for k, v in new.items()}
        for k, v in new.items():
            setattr(bd, k, np.concatenate([getattr(bd, k), v]))
        # kernels need (i, j) order for the lookup; bond indices of earlier installs shift
        # (the breakage log also records the ball ids i, j)
        order = np.lexsort((bd.j, bd.i))
        for k in new:
            setattr(bd, k, getattr(bd, k)[order])
        # every row logged so far + one per element that may still break
        self.log.ensure(int(self.log.n[0]) + int(bd.state.sum()))
        self._touch()
        return len(new["i"])

    # ------------------------------------------------------------------ changing
    def delete_balls(self, ids):
        """Remove balls (ids stay valid, ``alive`` = 0); their bonds are removed."""
        b = self.balls
        b.alive[ids] = 0
        b.vel[ids] = 0.0
        b.force[ids] = 0.0
        dead = b.alive == 0
        bd = self.bonds
        bd.active[dead[bd.i] | dead[bd.j]] = 0
        self._touch()

    def drop_deleted_bonds(self):
        """Take the bonds of deleted balls out of the bond arrays (``delete_balls`` leaves
        them there, inactive, and every bond loop of every later step passes over them: a
        third of the bonds after a box assembly's cuts). Later bonds' indices shift; those
        the breakage log and the Verlet list hold are renumbered (-1: a bond taken out).
        Returns how many went."""
        b, bd, log, pr = self.balls, self.bonds, self.log, self.pairs
        gone = (b.alive[bd.i] == 0) | (b.alive[bd.j] == 0)
        if not gone.any():
            return 0
        index = np.where(gone, -1, np.cumsum(~gone) - 1)
        for ids in (log.bond[: log.n[0]], pr.bond[: pr.n[0]]):
            ids[:] = np.where(ids >= 0, index[np.maximum(ids, 0)], -1)
        for f in fields(bd):
            setattr(bd, f.name, getattr(bd, f.name)[~gone])
        self._touch()
        return int(gone.sum())

    def enable_crushing(self, clumps, sigma0, m, d0, seed, fines_diameter=0.0, every=100,
                        criterion="largest_contact_force"):
        """Free clumps ``clumps`` split when their ``criterion``'s stress (crushing.CRITERIA)
        reaches a Weibull strength (sigma0 [Pa] at equivalent diameter d0 [m], modulus m;
        crushing.py), checked every ``every`` steps; pieces below ``fines_diameter`` [m]
        are removed as fines. The record: ``split_log``."""
        crushing.enable(self, clumps, sigma0, m, d0, seed, fines_diameter, every, criterion)

    def crushing_settings(self):
        """The splitting law enabled (crushing.settings), None if stones do not split."""
        return crushing.settings(self)

    def accumulate_damage(self, exponent, endurance):
        """One cycle's fatigue damage of the splitting stones (crushing.accumulate_damage)."""
        return crushing.accumulate_damage(self, exponent, endurance)

    def scale_bond_strength(self, factor, bonds=None):
        """Multiply tensile strength and cohesion of ``bonds`` (default all) by factor."""
        idx = slice(None) if bonds is None else bonds
        self.bonds.sigc[idx] *= factor
        self.bonds.coh[idx] *= factor

    def set_damping(self, alpha=None, balls=None, clump_alpha=None, clumps=None):
        """PFC local damping per body. ``alpha`` for ``balls`` (default: all balls, and
        the default for balls added later); ``clump_alpha`` for ``clumps`` likewise."""
        if alpha is not None:
            if balls is None:
                self.prm[P.ALPHA] = alpha
                self.balls.damp[:] = alpha
            else:
                self.balls.damp[balls] = alpha
        if clump_alpha is not None:
            if clumps is None:
                self.prm[P.ALPHA_CLUMP] = clump_alpha
                self.clumps.damp[:] = clump_alpha
            else:
                self.clumps.damp[clumps] = clump_alpha

    def set_density_scaling(self, dt=None):
        """Fixed timestep ``dt`` with density scaling: at every neighbour rebuild each free
        ball's and free clump's inertial mass (and moment) is raised so that ``dt`` is
        stable, while gravity acts on the real mass. ``None``: back to the automatic critical timestep and the
        real inertial masses."""
        p, b = self.prm, self.balls
        if dt is None:
            p[P.DSCALE] = 0.0
            p[P.AUTO_DT] = 1.0
            free = b.clump < 0
            b.minv[free] = 1.0 / b.mass[free]
            b.iinv[free] = 1.0 / b.inertia[free]
            c = self.clumps
            c.imass[:] = c.mass
            c.iinertia[:] = c.inertia
            peb = ~free
            b.minv[peb] = 1.0 / c.mass[b.clump[peb]]
        else:
            p[P.DT] = float(dt)
            p[P.AUTO_DT] = 0.0
            p[P.DSCALE] = 1.0
        self._touch()

    def set_gravity(self, g):
        self.prm[P.GX], self.prm[P.GY] = g

    @property
    def gravity(self):
        """Gravity vector [m/s^2]."""
        return float(self.prm[P.GX]), float(self.prm[P.GY])

    @property
    def thickness(self):
        """Out-of-plane thickness t [m]."""
        return float(self.prm[P.THICK])

    @property
    def n_breakages(self):
        """Flat-joint elements broken so far (rows of the breakage log)."""
        return int(self.log.n[0])

    def _touch(self):
        self.cnt[2] = 1      # force a neighbour rebuild before the next step

    # ------------------------------------------------------------------ running
    @property
    def step(self):
        return int(self.cnt[0])

    @property
    def time(self):
        return float(self.prm[P.TIME])

    @property
    def dt(self):
        return float(self.prm[P.DT])

    @property
    def n_rebuilds(self):
        return int(self.cnt[1])

    def prepare(self):
        """Make the model ready to step without stepping: skin, domain, Verlet lists
        (history carried), the forces before the first step. Returns self."""
        p, b = self.prm, self.balls
        live = b.alive.astype(bool)
        if self.skin is None:
            self.skin = 0.5 * float(b.rad[live].max())
        p[P.SKIN] = self.skin
        if self.domain is None:
            pts = [b.pos[live] - b.rad[live, None], b.pos[live] + b.rad[live, None]]
            if len(self.walls):
                pts.append(self.walls.seg[:, :2])
                pts.append(self.walls.seg[:, 2:])
            pts = np.vstack(pts)
            lo, hi = pts.min(axis=0), pts.max(axis=0)
            m = 0.5 * (hi - lo).max()
            self.domain = tuple(float(v) for v in (lo[0] - m, lo[1] - m, hi[0] + m, hi[1] + m))
        p[P.XMIN], p[P.YMIN], p[P.XMAX], p[P.YMAX] = self.domain
        if self.cnt[2]:
            self._rebuild()
        if self.step == 0 and not self._prepared:
            # forces before the first step: the weight (the initial state has no history)
            reset_forces(p[P.GX], p[P.GY], b.mass, b.fext, b.force, b.moment, b.clump, b.alive)
        self._prepared = True

    def _run_state(self):
        return RunState(self.prm, self.cnt, self.err, self.eacc, self.coef)

    def _rebuild(self):
        p = self.prm
        pr, wp = rebuild_lists(self._run_state(), self.balls.kernel(), self.walls.kernel(),
                               self.pairs.kernel(), self.wpairs.kernel(), self.bonds.kernel())
        self.pairs.take(pr)
        self.wpairs.take(wp)
        dtc = self.critical_dt()
        if p[P.AUTO_DT]:
            if dtc >= 1e30:
                dtc = self._lonely_dt()
            p[P.DT] = p[P.DT_SAFETY] * dtc
        if p[P.DT] <= 0.0:
            raise ValueError("no timestep: give dt or add contacts/walls (dt_crit undefined)")

    def _lonely_dt(self):
        """dt_crit when nothing is near anything yet: the lightest ball in one contact
        with its twin at the stiffest material (so the first contacts are safe)."""
        b = self.balls
        live = b.alive == 1
        r = float(b.rad[live].max())     # the stiffest contact: ball-facet (ri = 0), largest R
        n = self.coef.shape[0]
        k = max(sum(contact_stiffness(self._layout, tuple(self.coef[ma, mb]), 0.0, r,
                                      self.thickness)[:2])
                for ma in range(n) for mb in range(n))
        return float(np.sqrt(b.mass[live].min() / k / 2.0))

    def critical_dt(self):
        """min sqrt(m/k_tr) and sqrt(I/k_rot) over the free balls and free clumps, from the
        current Verlet lists and bonds (integrate.critical_dt)."""
        return timestep(self._layout)(self._run_state(), self.balls.kernel(),
                                      self.clumps.kernel(), self.pairs.kernel(),
                                      self.wpairs.kernel(), self.walls.kernel(), self.bonds.kernel())

    def _body_springs(self):
        """The free bodies' springs as critical_dt sums them: (kind, id, mass, inertia,
        inertial mass, inertial moment, k_tr, k_rot) arrays over the live free balls with
        springs, then the free clumps with springs (kind 0 ball, 1 clump)."""
        self.prepare()
        ktr, krot = springs(self._layout)(self._run_state(), self.balls.kernel(), self.pairs.kernel(),
                                          self.wpairs.kernel(), self.walls.mat, self.bonds.kernel())
        b, c = self.balls, self.clumps
        ball = np.flatnonzero((b.alive == 1) & (b.clump < 0) & (ktr > 0.0))
        ctr, crot = clump_stiffness(self._layout)(self._run_state(), b.kernel(), c.kernel(),
                                                  self.pairs.kernel(), self.wpairs.kernel(),
                                                  self.walls.kernel(), self.bonds.kernel())
        clump = np.flatnonzero((c.held == 0) & (ctr > 0.0))
        cat = np.concatenate
        return (cat([np.zeros(len(ball), int), np.ones(len(clump), int)]), cat([ball, clump]),
                cat([b.mass[ball], c.mass[clump]]), cat([b.inertia[ball], c.inertia[clump]]),
                cat([1.0 / b.minv[ball], c.imass[clump]]), cat([1.0 / b.iinv[ball], c.iinertia[clump]]),
                cat([ktr[ball], ctr[clump]]), cat([krot[ball], crot[clump]]))

    def timestep_limit(self):
        """What sets dt_crit: the limiting body ("ball" or "clump", its id, its largest
        radius [m], mass [kg], "translation" or "rotation", the bonds of a ball) and the
        per-body dt_crit's percentiles (1, 10, 50) [s], from the springs critical_dt sums
        (the current Verlet lists and bonds), with the inertia the bodies have now
        (density scaling included)."""
        kind, ids, _, _, im, ii, ktr, krot = self._body_springs()
        with np.errstate(divide="ignore"):
            dt_tr = np.sqrt(im / ktr)
            dt_rot = np.where(krot > 0.0, np.sqrt(ii / np.where(krot > 0, krot, 1.0)), np.inf)
        per_body = np.minimum(dt_tr, dt_rot)
        k = int(np.argmin(per_body))
        i, b = int(ids[k]), self.balls
        active = self.bonds.active == 1
        if kind[k] == 0:
            what = dict(body="ball", ball=i, radius=float(b.rad[i]), mass=float(b.mass[i]),
                        bonds=int(np.sum(self.bonds.i[active] == i) + np.sum(self.bonds.j[active] == i)))
        else:
            peb = (b.clump == i) & (b.alive == 1)
            what = dict(body="clump", clump=i, radius=float(b.rad[peb].max()),
                        mass=float(self.clumps.mass[i]), pebbles=int(peb.sum()))
        return dict(what, springs="rotation" if dt_rot[k] < dt_tr[k] else "translation",
                    dt_crit=float(per_body[k]),
                    percentiles=[float(v) for v in np.percentile(per_body, [1, 10, 50])])

    def inertial_masses(self):
        """Each ball's share of the inertial mass [kg]: a free ball's own (density scaling
        included), a pebble's mass times its clump's inertial-to-real ratio (its clump's
        inertial mass spread over the pebbles by mass, so that a sum over them counts the
        clump once; 1 / minv of a pebble is the whole clump's, for its contacts' dashpots)."""
        b, c = self.balls, self.clumps
        out = 1.0 / b.minv
        peb = b.clump >= 0
        out[peb] = b.mass[peb] * c.imass[b.clump[peb]] / c.mass[b.clump[peb]]
        return out

    def added_inertia(self):
        """The inertial mass density scaling adds to the free bodies (balls and clumps)
        now, as a fraction of their real mass (0 without density scaling)."""
        b, c = self.balls, self.clumps
        free = (b.alive == 1) & (b.clump < 0)
        loose = c.held == 0
        real = b.mass[free].sum() + c.mass[loose].sum()
        inertial = (1.0 / b.minv[free]).sum() + c.imass[loose].sum()
        return float(inertial / real - 1.0) if real > 0 else 0.0

    def scaled_timestep(self, added_inertia_max):
        """The largest fixed dt whose density scaling (``set_density_scaling``) adds at most
        ``added_inertia_max`` x the free bodies' real mass to their inertial mass, and as
        much of their moment of inertia: density scaling raises only the bodies whose own
        dt_crit is below dt / f (the few smallest, an artefact of the ball model), so a
        small added fraction buys much of the dt that the typical body allows. Free balls
        and free clumps (rigid stones) alike. At least the automatic dt (no inertia
        added). Reads the current contacts: call it on the specimen as it is loaded."""
        _, _, m, inertia, _, _, kt, kr = self._body_springs()
        f = float(self.prm[P.DT_SAFETY])

        def added(dt):
            s2 = (dt / f) ** 2
            return max(np.maximum(kt * s2 - m, 0.0).sum() / m.sum(),
                       np.maximum(kr * s2 - inertia, 0.0).sum() / inertia.sum())

        with np.errstate(divide="ignore"):
            lo = f * float(np.sqrt(np.minimum(m / kt, inertia / kr).min()))   # the automatic dt
        hi = lo
        while added(2.0 * hi) <= added_inertia_max:
            hi *= 2.0
        hi *= 2.0
        for _ in range(60):          # added() grows monotonically with dt: bisection
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if added(mid) <= added_inertia_max else (lo, mid)
        return lo

    def run(self, n_steps, callback=None, every=None, control=None):
        """Advance ``n_steps`` steps. With ``callback``, call ``callback(sim)`` every
        ``every`` steps (default: once at the end); the callback may change velocities,
        parameters, delete balls... and may return True to stop early.
        ``control``: a built ``control.Control`` run inside the loop; the run stops early
        when one of its controllers raises an event (``control.event``).
        Raises SimulationError if a guard trips (step, ball id, value in the message)."""
        every = n_steps if every is None else max(1, int(every))
        ctl = _NO_CONTROL if control is None else control.arrays
        done = 0
        while done < n_steps:
            k = min(every, n_steps - done)
            while k > 0:              # a split (crushing.py) stops the kernel mid-chunk
                self.prepare()
                status, steps = self._run_kernel(k, ctl)
                if status == P.CONTROL_EVENT:
                    return self
                k -= steps
                done += steps
            if callback is not None and callback(self):
                break
        return self

    def _run_kernel(self, k, ctl=None):
        b = self.balls
        status, steps, pr, wp = stepper(self._layout)(
            k, self._run_state(), b.kernel(), self.walls.kernel(), self.clumps.kernel(),
            self.pairs.kernel(), self.wpairs.kernel(), self.bonds.kernel(), self.log.kernel(),
            _NO_CONTROL if ctl is None else ctl)
        self.pairs.take(pr)
        self.wpairs.take(wp)
        every = int(self.prm[P.CRUSH_EVERY])
        if status in (P.STONES_OVERLOADED, P.CONTROL_EVENT) and every and self.step % every == 0:
            crushing.split_overloaded(self)    # the kernel's check, or one an event pre-empted
        if status in (P.CONTROL_EVENT, P.STONES_OVERLOADED):
            return status, steps
        if status != P.OK:
            i, v = int(self.err[0]), float(self.err[1])
            raise SimulationError(
                f"{P.STATUS_TEXT[status]} at step {self.step} (t = {self.time:.6g} s): "
                f"ball {i} (stone {int(b.stone[i])}, clump {int(b.clump[i])}), value {v:.6g}; "
                f"pos {b.pos[i].tolist()}, vel {b.vel[i].tolist()}, domain {self.domain}, "
                f"vmax {self.prm[P.VMAX]:g}; all offending balls: {self._offenders()}")
        return status, steps

    def _offenders(self, limit=20):
        b, p = self.balls, self.prm
        live = b.alive == 1
        bad = ~np.isfinite(b.pos).all(1) | ~np.isfinite(b.vel).all(1) | ~np.isfinite(b.omega)
        bad |= (b.vel ** 2).sum(1) > p[P.VMAX] ** 2
        bad |= (b.pos[:, 0] < p[P.XMIN]) | (b.pos[:, 0] > p[P.XMAX])
        bad |= (b.pos[:, 1] < p[P.YMIN]) | (b.pos[:, 1] > p[P.YMAX])
        ids = np.nonzero(bad & live)[0]
        more = f" ... ({len(ids)} in total)" if len(ids) > limit else ""
        return ids[:limit].tolist().__repr__() + more

    def inertial_number(self, shear_rate, pressure, d=None, rho=None):
        """I = shear_rate * d * sqrt(rho / p) for a stage: quasi-static while I << 1e-3.
        d, rho default to the mean diameter and mean density of the live balls."""
        b = self.balls
        live = b.alive == 1
        if d is None:
            d = 2.0 * float(b.rad[live].mean())
        if rho is None:
            area = np.pi * b.rad[live] ** 2 * self.prm[P.THICK]
            rho = float((b.mass[live] / area).mean())
        return output.inertial_number(shear_rate, d, rho, pressure)

    # ------------------------------------------------------------------ checkpoint
    def save_checkpoint(self, path):
        """Write the whole state to ``path`` (npz, atomic: temp file + rename)."""
        save_state(path, self)

    @classmethod
    def load_checkpoint(cls, path):
        """Restore a Simulation saved by ``save_checkpoint``; continuing it gives bitwise
        the same trajectory as a run that never stopped."""
        sim = cls.__new__(cls)
        load_state(path, sim)
        return sim

    # ------------------------------------------------------------------ measurements
    def wall_force(self, ids=None):
        """Force exerted by the balls on segments ``ids`` (all if None) [N], (k, 2)."""
        return output.wall_force(self, ids)

    def wall_moment(self, ids=None):
        """Moment of that force about each segment's rotation centre [N m]."""
        return output.wall_moment(self, ids)

    def clump_force(self, cid):
        """(force [N], moment about the centre of mass [N m]) on clump ``cid``."""
        return output.clump_force(self, cid)

    def local_damping_force(self, ids=None, clumps=False):
        """Local damping force on balls (clumps if ``clumps``) ``ids`` (all if None) in the
        last step [N], (k, 2)."""
        return output.local_damping_force(self, ids, clumps)

    def contact_list(self):
        """Contacts carrying force: i, j (wall: -1 - segment), fx, fy on j, x, y."""
        return output.contact_list(self)

    def contact_state(self):
        """Persistent per-contact state of the law's sub-models (slip_work, ...) [J]."""
        return output.contact_state(self)

    def intact_bonds(self):
        """(n_bonds,) bool: interface present with >= 1 intact element."""
        return output.intact_bonds(self)

    def fragments(self, n_balls=None):
        """Fragment label of balls 0..n_balls-1 (default all; -1: dead), by lowest ball id."""
        return output.fragments(self, n_balls)

    def bond_list(self):
        """Flat joints with per-element state and forces."""
        return output.bond_list(self)

    def breakages(self):
        """Breakage log (step, time, bond, elem, i, j, stone, mode, x, y, stress)."""
        return output.breakages(self)

    def split_log(self):
        """Every split of a rigid stone so far (state.SplitLog's columns)."""
        n = len(self.splits)
        return {f.name: getattr(self.splits, f.name)[:n].copy() for f in fields(self.splits)}

    def energies(self):
        """Kinetic, potential, elastic and dissipated energies [J]."""
        return output.energies(self)
