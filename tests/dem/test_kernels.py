"""Kernel-level checks on tiny arrays: neighbour lists vs brute force, history merge,
segment contacts at joints, flat-joint strip integrals."""
import numpy as np

from ballaststudy.dem.bonds import strip_integrals
from ballaststudy.dem.neighbours import build_pairs, build_wall_pairs, carry_rows, match_rows


def brute_pairs(pos, rad, alive, clump, skin):
    n = len(rad)
    d = np.hypot(*(pos[:, None] - pos[None]).transpose(2, 0, 1))
    ok = (d < rad[:, None] + rad[None] + skin) & np.triu(np.ones((n, n), bool), 1)
    ok &= (alive[:, None] == 1) & (alive[None] == 1)
    ok &= ~((clump[:, None] >= 0) & (clump[:, None] == clump[None]))
    return set(zip(*np.nonzero(ok)))


def test_cell_list_matches_brute_force_and_reports_capacity():
    rng = np.random.default_rng(1)
    n = 1500
    pos = rng.uniform(0, 0.3, (n, 2))
    rad = rng.uniform(0.002, 0.006, n)
    alive = np.ones(n, np.uint8)
    alive[5] = 0
    clump = -np.ones(n, np.int32)
    clump[10:20] = 0
    oi = np.zeros(50000, np.int32)
    oj = oi.copy()
    none = np.zeros(n, np.uint8)
    c = build_pairs(pos, rad, alive, none, clump, 0.002, -0.01, -0.01, 0.31, 0.31, oi, oj)
    ref = brute_pairs(pos, rad, alive, clump, 0.002)
    got = set(zip(oi[:c].tolist(), oj[:c].tolist()))
    assert c == len(ref) and got == ref, f"{c} pairs found, {len(ref)} expected"
    assert np.all(np.diff(oi[:c]) >= 0), "rows not grouped by ascending i"
    small = np.zeros(10, np.int32)
    assert build_pairs(pos, rad, alive, none, clump, 0.002, -0.01, -0.01, 0.31, 0.31,
                       small, small.copy()) == -c
    # buried balls (the largest among them: the cells keep their size) are left out, and
    # the pairs left keep their order
    buried = np.zeros(n, np.uint8)
    buried[30:60] = 1
    buried[np.argmax(rad)] = 1
    bi, bj = np.zeros(50000, np.int32), np.zeros(50000, np.int32)
    cb = build_pairs(pos, rad, alive, buried, clump, 0.002, -0.01, -0.01, 0.31, 0.31, bi, bj)
    keep = (buried[oi[:c]] == 0) & (buried[oj[:c]] == 0)
    assert cb == keep.sum() < c
    assert np.array_equal(bi[:cb], oi[:c][keep]) and np.array_equal(bj[:cb], oj[:c][keep])


def test_history_follows_pairs_across_rebuild():
    old_i = np.array([0, 0, 1, 3], np.int32)
    old_j = np.array([1, 4, 2, 5], np.int32)
    old_h = np.array([[1.0, 2.0], [3.0, 4.0], [5.0, 6.0], [7.0, 8.0]])
    new_i = np.array([0, 1, 2, 3], np.int32)
    new_j = np.array([4, 2, 3, 5], np.int32)
    found = match_rows(old_i, old_j, 4, new_i, new_j, 4, 6)
    assert found.tolist() == [1, 2, -1, 3]
    out = np.full((4, 2), -1.0)
    carry_rows(found, old_h, out)
    assert out.tolist() == [[3.0, 4.0], [5.0, 6.0], [0.0, 0.0], [7.0, 8.0]]
    lap = np.full(4, -1.0)
    carry_rows(found, np.array([0.1, 0.2, 0.3, 0.4]), lap)
    assert lap.tolist() == [0.2, 0.3, 0.0, 0.4]


def test_wall_pairs_brute_force():
    rng = np.random.default_rng(3)
    pos = rng.uniform(-0.1, 0.4, (400, 2))
    rad = rng.uniform(0.002, 0.01, 400)
    seg = np.array([[0, 0, 0.3, 0], [0.3, 0, 0.3, 0.3], [0.05, 0.1, 0.2, 0.25]], float)
    oi = np.zeros(2000, np.int32)
    os_ = oi.copy()
    clear = np.zeros(400)
    c = build_wall_pairs(pos, rad, np.ones(400, np.uint8), np.zeros(400, np.uint8), seg, 0.003, oi, os_, clear)
    ref = set()
    gap = np.full(400, np.inf)
    for i in range(400):
        for s, (x0, y0, x1, y1) in enumerate(seg):
            e = np.array([x1 - x0, y1 - y0])
            u = np.clip(((pos[i] - [x0, y0]) @ e) / (e @ e), 0, 1)
            d = np.hypot(*(pos[i] - [x0, y0] - u * e))
            if d < rad[i] + 0.003:
                ref.add((i, s))
            else:
                gap[i] = min(gap[i], d - rad[i])
    assert set(zip(oi[:c].tolist(), os_[:c].tolist())) == ref
    # clear: a lower bound of the gap to every unlisted segment, never below the skin
    assert np.all(clear <= gap + 1e-15) and np.all(clear >= 0.003 - 1e-15)
    buried = np.zeros(400, np.uint8)
    buried[::3] = 1
    cb = build_wall_pairs(pos, rad, np.ones(400, np.uint8), buried, seg, 0.003, oi, os_, clear)
    assert set(zip(oi[:cb].tolist(), os_[:cb].tolist())) == {(i, s) for i, s in ref if not buried[i]}


def test_strip_integrals():
    # bonded: int over [-1, 1] of (g - th s) = 2 g ; int s (g - th s) = -2 th / 3
    i0, i1 = strip_integrals(0.3, 0.5, -1.0, 1.0, False)
    assert np.isclose(i0, 0.6) and np.isclose(i1, -1.0 / 3.0)
    # compression only: g(s) = 0.3 - 0.5 s < 0 for s > 0.6 -> int_{0.6}^{1} = -0.04
    i0, _ = strip_integrals(0.3, 0.5, -1.0, 1.0, True)
    assert np.isclose(i0, -0.04), i0
    assert strip_integrals(0.1, 0.0, -1.0, 1.0, True) == (0.0, 0.0)


def test_verlet_validity_test_misses_no_contact():
    """A packing thrown sideways and down into a wall corner: the lazy rebuild (exact test
    on displacements relative to the common shift, per-ball wall clearance) must give the
    same motion as rebuilding before every step (only rounding may differ)."""
    from ballaststudy.dem import ContactMaterial, Simulation

    from .generate import random_disks

    def model():
        sim = Simulation(gravity=(0, -50.0), dt=1e-5, domain=(-0.1, -0.1, 0.3, 0.3), skin=0.001)
        sim.set_contact_material(ContactMaterial(E=1e7, mu=0.4, beta_n=0.1))
        sim.add_wall([(0.0, 0.2), (0.0, 0.0), (0.2, 0.0)])
        x, y, r, vx, vy = random_disks(60, 0.02, 0.12, 0.01, 0.003, 0.005, seed=9, vmax=0.3)
        sim.add_balls(x, y, r, 2650.0, vx=vx - 1.5, vy=vy - 0.5)
        return sim
    lazy, eager = model(), model()
    seen = []
    lazy.run(3000, callback=lambda s: seen.append(len(s.contact_list()["i"])), every=50)
    eager.run(3000, callback=lambda s: s._touch(), every=1)
    assert eager.n_rebuilds > 10 * lazy.n_rebuilds > 0
    dx = np.abs(lazy.balls.pos - eager.balls.pos).max()
    assert dx < 1e-9, f"lazy and eager neighbour lists diverge by {dx:.3e} m"
    assert max(seen) > 30, f"too few contacts to test: {max(seen)}"
