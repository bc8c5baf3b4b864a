"""Particle coordination number and ghost particles (thesis 4.5.1, l. 1065-1074).

Particle = ballast stone as it is now = fragment. Its coordination number is "the number
of contacted neighbor particles" (l. 1065): the number of *distinct* other fragments it
touches through ball-ball contacts that carry force (|normal force| > threshold).
Contacts between balls of the same fragment are internal and do not count.

The plate: the thesis does not say whether the pressing plate counts. A stone pressed by
the plate on one supporting stone carries the load, so by the thesis' reason for the
definition ("particles that do not take a significant structural load", l. 1067) it is
not a ghost; with ``count_plate_contact`` (default) all non-ballast balls (the plate's
pebbles) together count as one neighbour.

Ghost particles (l. 1074): fragments with <= 2 such contacts, excluding
  - fragments in contact with the container (they "do take a significant loading"):
    a per-ball flag from the engine's ball-wall contacts, or geometry within a tolerance
    of the walls;
  - fragments in the shoulder area (they "will not take loads in any cases"): the
    thesis gives no numbers (Fig. 4-17 only), so here: centroid above
    (plate bottom - shoulder_depth) and outside the plate's x-range.
"""
import numpy as np


def coordination_numbers(labels, n_fragments, contact_i, contact_j, contact_fn,
                         threshold=0.0, count_plate_contact=True):
    """Coordination number of each fragment, (n_fragments,) int.

    labels: (n,) fragment per ball, -1 for non-ballast balls (plate pebbles, loading ball).
    contact_i, contact_j, contact_fn: contacts (ball ids) and their normal force [N] (any
        sign convention: the magnitude is compared with ``threshold``; the magnitude of the
        total contact force does as well). Wall contacts (j < 0, engine convention) are
        ignored here.
    """
    labels = np.asarray(labels)
    ci = np.asarray(contact_i, dtype=np.int64)
    cj = np.asarray(contact_j, dtype=np.int64)
    fn = np.abs(np.asarray(contact_fn, float))
    keep = (fn > threshold) & (ci >= 0) & (cj >= 0)
    fi, fj = labels[ci[keep]], labels[cj[keep]]
    plate = n_fragments                      # id of "the plate" as a neighbour
    if count_plate_contact:
        fi = np.where(fi < 0, plate, fi)
        fj = np.where(fj < 0, plate, fj)
    ok = (fi >= 0) & (fj >= 0) & (fi != fj) & ~((fi == plate) & (fj == plate))
    a = np.concatenate([fi[ok], fj[ok]])
    b = np.concatenate([fj[ok], fi[ok]])
    pairs = np.unique(np.stack([a, b], axis=1), axis=0) if a.size else np.zeros((0, 2), np.int64)
    pairs = pairs[pairs[:, 0] < n_fragments]
    return np.bincount(pairs[:, 0], minlength=n_fragments).astype(np.int64)


def touching_container(labels, n_fragments, pos=None, rad=None, x_min=None, x_max=None,
                       y_bottom=None, tolerance=0.0, ball_touches_container=None):
    """(n_fragments,) bool: a ball of the fragment touches the container (side walls or
    bottom). Use the engine's per-ball flag ``ball_touches_container`` (from ball-wall
    contacts) when given; otherwise geometry: a ball whose surface is within
    ``tolerance`` [m] of a wall."""
    labels = np.asarray(labels)
    if ball_touches_container is not None:
        t = np.asarray(ball_touches_container, bool)
    else:
        p = np.asarray(pos, float)
        r = np.asarray(rad, float)
        t = ((p[:, 0] - r <= x_min + tolerance) | (p[:, 0] + r >= x_max - tolerance)
             | (p[:, 1] - r <= y_bottom + tolerance))
    sel = t & (labels >= 0)
    out = np.zeros(n_fragments, bool)
    out[labels[sel]] = True
    return out


def container_flags_from_contacts(n_balls, contact_i, contact_j, container_walls):
    """(n_balls,) bool per-ball "touches the container" from the engine's contact list,
    where a wall contact has ``j = -1 - segment`` (``Simulation.contact_list``).
    container_walls: segment ids of the container (bottom segments and side walls)."""
    ci = np.asarray(contact_i, dtype=np.int64)
    cj = np.asarray(contact_j, dtype=np.int64)
    wall = cj < 0
    hit = np.isin(-1 - cj[wall], np.asarray(container_walls, dtype=np.int64))
    out = np.zeros(int(n_balls), bool)
    out[ci[wall][hit]] = True
    return out


def in_shoulder(centroids, plate_x_mid, plate_half_width, plate_bottom_y, shoulder_depth):
    """(n_fragments,) bool: centroid above plate_bottom_y - shoulder_depth and outside
    the plate's x-range [mid - half_width, mid + half_width]."""
    c = np.asarray(centroids, float)
    outside = np.abs(c[:, 0] - plate_x_mid) > plate_half_width
    return outside & (c[:, 1] > plate_bottom_y - shoulder_depth)


def ghost_particles(coordination, excluded, max_contacts=2):
    """(n_fragments,) bool: ghost = not excluded and coordination <= max_contacts."""
    return (np.asarray(coordination) <= max_contacts) & ~np.asarray(excluded, bool)
