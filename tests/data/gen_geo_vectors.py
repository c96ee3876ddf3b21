#!/usr/bin/env python3
"""Generate tests/data/geo_vectors.csv: reference look angles for src/geo.rs.

The reference is pymap3d.geodetic2aer (WGS84 ellipsoid, its default), an implementation
independent of this crate. Cases are deterministic (seeded `random`), so re-running the
script with the same pymap3d and Python versions reproduces the file byte for byte.

    pip install pymap3d==3.2.0
    python3 tests/data/gen_geo_vectors.py > tests/data/geo_vectors.csv

Target positions are placed with pymap3d.aer2geodetic from a chosen bearing, elevation
and range, then printed with Python's shortest round-trip float repr (which Rust parses
to the same f64), and the reference look angles are computed from those printed values.

pymap3d's enu2aer sets east, north and up components below 1 mm to zero ("for
singularity stability"). At ranges of a metre or so that would move its angles by up to
0.05 degrees, so a case whose geodetic2aer angles differ from atan2 of pymap3d's own
unrounded geodetic2enu by more than 1e-6 degrees is drawn again: every row's reference
is geodetic2aer's output, unaffected by that rounding.

Columns: kind, vehicle lat/lon/alt, target lat/lon/alt (degrees, metres above the
ellipsoid), then geodetic2aer's azimuth (bearing) and elevation (degrees) and slant
range (m), and the horizontal distance hypot(east, north) from geodetic2enu (m).
"""

import math
import platform
import random
import sys

import pymap3d

SEED = 20240611
# |elevation| bound for ordinary (not near-vertical) cases, so their bearing is defined.
MAX_EL = 80.0
ALT_MIN, ALT_MAX = -1000.0, 100_000.0


def reference(v, t):
    """(az, el, srange, hdist) from vehicle v to target t, or None if pymap3d's 1 mm
    rounding in enu2aer moved the angles."""
    az, el, sr = pymap3d.geodetic2aer(t[0], t[1], t[2], v[0], v[1], v[2], deg=True)
    e, n, u = pymap3d.geodetic2enu(t[0], t[1], t[2], v[0], v[1], v[2], deg=True)
    hdist = math.hypot(e, n)
    el_raw = math.degrees(math.atan2(u, hdist))
    if abs(el - el_raw) > 1e-6:
        return None
    if hdist > 1.0:
        az_raw = math.degrees(math.atan2(e, n)) % 360.0
        d = abs(az - az_raw) % 360.0
        if min(d, 360.0 - d) > 1e-6:
            return None
    return az, el, sr, hdist


def place(v, az, el, srange):
    """Target at the given look angles from v, or None if it leaves the valid domain."""
    lat, lon, alt = pymap3d.aer2geodetic(az, el, srange, v[0], v[1], v[2], deg=True)
    lon = (lon + 180.0) % 360.0 - 180.0
    if not (abs(lat) <= 85.5 and ALT_MIN <= alt <= ALT_MAX):
        return None
    return (lat, lon, alt)


def log_uniform(rng, lo, hi):
    return math.exp(rng.uniform(math.log(lo), math.log(hi)))


def random_vehicle(rng, lat_max=85.0):
    return (rng.uniform(-lat_max, lat_max), rng.uniform(-180.0, 180.0), rng.uniform(-100.0, 5000.0))


def main():
    rng = random.Random(SEED)
    rows = []

    def add(kind, v, t, must=False):
        ref = reference(v, t)
        if ref is None:
            if must:
                raise SystemExit(f"fixed case {v} -> {t} is affected by pymap3d's 1 mm rounding")
            return False
        rows.append((kind, v, t) + ref)
        return True

    def add_random(kind, count, make_vehicle, r_lo, r_hi, el_lo=-MAX_EL, el_hi=MAX_EL, az=None):
        made = 0
        while made < count:
            v = make_vehicle()
            a = rng.uniform(0.0, 360.0) if az is None else az
            t = place(v, a, rng.uniform(el_lo, el_hi), log_uniform(rng, r_lo, r_hi))
            if t is not None and add(kind, v, t):
                made += 1

    # Hand-checkable and boundary cases.
    fixed = [
        ("fixed", (0.0, 0.0, 0.0), (0.0, 0.0, 1000.0)),  # straight up at the equator
        ("fixed", (45.0, 10.0, 500.0), (45.0, 10.0, 100.0)),  # straight down
        ("fixed", (0.0, 0.0, 0.0), (0.0, 0.01, 0.0)),  # east along the equator
        ("fixed", (0.0, 0.0, 0.0), (0.01, 0.0, 0.0)),  # north along the meridian
        ("fixed", (30.0, 50.0, 0.0), (29.99, 50.0, 0.0)),  # south
        ("fixed", (85.0, 0.0, 1000.0), (84.99, 0.5, 0.0)),
        ("fixed", (-85.0, 45.0, 1000.0), (-84.9, 44.0, 0.0)),
        ("antimeridian", (0.0, 179.99, 0.0), (0.0, -179.99, 0.0)),
        ("antimeridian", (0.0, -179.99, 0.0), (0.0, 179.99, 0.0)),
        ("antimeridian", (40.0, 179.99, 100.0), (40.01, -179.99, 0.0)),
        ("antimeridian", (-60.0, 180.0, 300.0), (-60.02, -179.97, 10.0)),
        ("antimeridian", (20.0, -180.0, 50.0), (20.001, 179.999, 0.0)),
    ]
    for kind, v, t in fixed:
        add(kind, v, t, must=True)

    # Short (1 m .. 100 m), medium (100 m .. 5 km) and long (5 km .. 50 km) ranges,
    # targets above and below the vehicle.
    add_random("short", 70, lambda: random_vehicle(rng), 1.0, 100.0)
    add_random("medium", 60, lambda: random_vehicle(rng), 100.0, 5000.0)
    # Long ranges: elevations a gimbal would see (a target 50 km away at 80 degrees
    # would be far above 100 km).
    add_random("long", 50, lambda: random_vehicle(rng), 5000.0, 50_000.0, -30.0, 30.0)
    # Latitudes near +-85.
    add_random(
        "high_lat",
        25,
        lambda: (rng.choice((-1.0, 1.0)) * rng.uniform(80.0, 85.0), rng.uniform(-180.0, 180.0), rng.uniform(0.0, 3000.0)),
        1.0,
        20_000.0,
        -30.0,
        30.0,
    )
    # Across the antimeridian: vehicle within 0.2 degrees of it, target on the far side.
    made = 0
    while made < 30:
        side = rng.choice((-1.0, 1.0))
        v = (rng.uniform(-85.0, 85.0), side * (180.0 - rng.uniform(0.0, 0.2)), rng.uniform(0.0, 3000.0))
        az = 90.0 if side > 0 else 270.0
        t = place(v, az + rng.uniform(-60.0, 60.0), rng.uniform(-30.0, 30.0), log_uniform(rng, 1.0, 50_000.0))
        if t is None or (t[1] > 0) == (side > 0):
            continue  # did not cross
        if add("antimeridian", v, t):
            made += 1
    # Near-vertical: within 1.5 degrees of straight up or down, plus exactly vertical.
    add_random("near_vertical", 20, lambda: random_vehicle(rng), 1.0, 5000.0, 88.5, 90.0)
    add_random("near_vertical", 20, lambda: random_vehicle(rng), 1.0, 5000.0, -90.0, -88.5)
    made = 0
    while made < 10:
        v = random_vehicle(rng)
        t = (v[0], v[1], v[2] + rng.choice((-1.0, 1.0)) * log_uniform(rng, 1.0, 1000.0))
        if ALT_MIN <= t[2] <= ALT_MAX and add("near_vertical", v, t):
            made += 1

    out = sys.stdout
    out.write("# Reference look angles for src/geo.rs (tests/geo.rs).\n")
    out.write(
        f"# Generated by tests/data/gen_geo_vectors.py with pymap3d {pymap3d.__version__} "
        f"(geodetic2aer, WGS84), Python {platform.python_version()}, seed {SEED}.\n"
    )
    out.write("# Regenerate: python3 tests/data/gen_geo_vectors.py > tests/data/geo_vectors.csv\n")
    out.write(
        "kind,vehicle_lat_deg,vehicle_lon_deg,vehicle_alt_m,target_lat_deg,target_lon_deg,"
        "target_alt_m,bearing_deg,elevation_deg,range_m,horizontal_m\n"
    )
    for kind, v, t, az, el, sr, hd in rows:
        fields = [kind] + [repr(float(x)) for x in (*v, *t, az, el, sr, hd)]
        out.write(",".join(fields) + "\n")


if __name__ == "__main__":
    main()
