"""Geometry and record-keeping shared by the YADE reference scripts.

Pure Python (no YADE import), so it can be used both inside `yade -n -x` and by
/usr/bin/python3 tools such as check_live.py.

Geometry
  cube_vertices      a cube of edge a, axis-aligned.
  shogi_vertices     a shogi piece (BENCHMARKS.md section 5): front view a pentagon with
                     base corners 81 deg and shoulders 117 deg (apex 144 deg); side view a
                     symmetric wedge, base thickness T, top thickness TOP_RATIO * T.
  shogi_tilt_frame   the piece's vertices rotated about its front bottom edge by a tilt.
Records
  write_csv, downsample, write_provenance, crossing_time.

Frame of a shogi piece (local): height along +z (base at z = 0), width along y (the
pentagon lies in the y-z plane), thickness along x (the wedge lies in the x-z plane).
Pieces therefore fall about an axis parallel to y, toward +x.
"""
import csv
import datetime
import json
import math
import os
import platform
import time

# Sizes from BENCHMARKS.md section 5 (height x width x base thickness), metres.
SHOGI_SIZES = {
    "king": (0.0320, 0.0287, 0.0097),
    "rook": (0.0310, 0.0277, 0.0093),
    "gold": (0.0300, 0.0267, 0.0088),
    "knight": (0.0290, 0.0255, 0.0083),
    "lance": (0.0280, 0.0235, 0.0080),
    "pawn": (0.0270, 0.0225, 0.0075),
}
SHOGI_DEFAULT = "king"          # the reference scripts use the king size
TOP_RATIO = 0.60                # top thickness / base thickness (section 5: 55-65 %)
BASE_ANGLE_DEG = 81.0
SHOULDER_ANGLE_DEG = 117.0
BOXWOOD_DENSITY = 950.0         # kg/m^3 (section 5: 900-1000)


def cube_vertices(a, origin=(0.0, 0.0, 0.0)):
    """8 vertices of the cube [ox, ox+a] x [oy, oy+a] x [oz, oz+a]."""
    ox, oy, oz = origin
    return [(ox + i * a, oy + j * a, oz + k * a) for i in (0, 1) for j in (0, 1) for k in (0, 1)]


def shogi_outline(height, width):
    """Front-view pentagon (y, z), counter-clockwise from the right base corner.

    Sides rise at the base angle (81 deg from the base); at the shoulder (interior angle
    117 deg) the roof turns so that it rises 117 - (180 - 81) = 18 deg above horizontal;
    the apex angle is then 540 - 2*81 - 2*117 = 144 deg.
    """
    base = math.radians(BASE_ANGLE_DEG)
    roof = math.radians(SHOULDER_ANGLE_DEG - (180.0 - BASE_ANGLE_DEG))  # 18 deg
    # apex height: z_s + y_s tan(roof) = height, y_s = width/2 - z_s / tan(base)
    z_s = (height - 0.5 * width * math.tan(roof)) / (1.0 - math.tan(roof) / math.tan(base))
    y_s = 0.5 * width - z_s / math.tan(base)
    return [(0.5 * width, 0.0), (y_s, z_s), (0.0, height), (-y_s, z_s), (-0.5 * width, 0.0)]


def shogi_thickness(z, height, thickness):
    """Wedge thickness at height z: linear from `thickness` at z = 0 to TOP_RATIO * it at the apex."""
    return thickness * (1.0 - (1.0 - TOP_RATIO) * z / height)


def shogi_vertices(size=SHOGI_DEFAULT):
    """10 vertices of a piece in its local frame (base centre at the origin).

    `size` is a key of SHOGI_SIZES or a (height, width, thickness) tuple.
    """
    h, w, t = SHOGI_SIZES[size] if isinstance(size, str) else size
    verts = []
    for (y, z) in shogi_outline(h, w):
        half = 0.5 * shogi_thickness(z, h, t)
        verts.append((-half, y, z))
        verts.append((half, y, z))
    return verts


def polyhedron_volume_centroid(verts, faces):
    """Volume and centroid of a closed polyhedron given triangulated faces (outward)."""
    vol, cx, cy, cz = 0.0, 0.0, 0.0, 0.0
    for (i, j, k) in faces:
        a, b, c = verts[i], verts[j], verts[k]
        d = (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
             + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0
        vol += d
        cx += d * (a[0] + b[0] + c[0]) / 4.0
        cy += d * (a[1] + b[1] + c[1]) / 4.0
        cz += d * (a[2] + b[2] + c[2]) / 4.0
    return vol, (cx / vol, cy / vol, cz / vol)


def shogi_faces():
    """Outward triangulation of shogi_vertices (2 pentagons, 5 quads)."""
    back = [0, 2, 4, 6, 8]    # x < 0 vertices, outline order (CCW seen from +x)
    front = [1, 3, 5, 7, 9]
    faces = []
    for k in range(1, 4):
        faces.append((front[0], front[k], front[k + 1]))
        faces.append((back[0], back[k + 1], back[k]))
    for k in range(5):
        a, b = k, (k + 1) % 5
        faces.append((back[a], back[b], front[b]))
        faces.append((back[a], front[b], front[a]))
    return faces


def shogi_critical_tilt_deg(size=SHOGI_DEFAULT):
    """Tilt about the front bottom edge at which the centre of mass is above that edge."""
    h, w, t = SHOGI_SIZES[size] if isinstance(size, str) else size
    vol, c = polyhedron_volume_centroid(shogi_vertices(size), shogi_faces())
    if vol < 0:
        raise ValueError("shogi_faces orientation is inward")
    return math.degrees(math.atan2(0.5 * t - c[0], c[2]))


def rotate_y(p, angle):
    """Rotate point p about the y axis by `angle` (rad); +angle tips +z toward +x."""
    x, y, z = p
    ca, sa = math.cos(angle), math.sin(angle)
    return (ca * x + sa * z, y, -sa * x + ca * z)


def shogi_tilt_frame(tilt_deg, origin=(0.0, 0.0, 0.0), size=SHOGI_DEFAULT, yaw180=False):
    """World vertices of a piece whose base centre is at `origin`, tilted by tilt_deg toward +x
    about its front bottom edge (x = +T/2, z = 0). yaw180 turns the piece to face -x first
    (not used by the wedge-symmetric piece, kept for completeness)."""
    h, w, t = SHOGI_SIZES[size] if isinstance(size, str) else size
    pivot = (0.5 * t, 0.0, 0.0)
    out = []
    for v in shogi_vertices(size):
        if yaw180:
            v = (-v[0], -v[1], v[2])
        r = rotate_y((v[0] - pivot[0], v[1], v[2]), math.radians(tilt_deg))
        out.append((r[0] + pivot[0] + origin[0], r[1] + origin[1], r[2] + origin[2]))
    return out


# ---------------------------------------------------------------- records

def downsample(rows, max_rows=2000):
    """Every k-th row (first and last kept) so that at most ~max_rows remain."""
    if len(rows) <= max_rows:
        return list(rows)
    k = int(math.ceil(len(rows) / float(max_rows - 1)))
    out = rows[::k]
    if out[-1] is not rows[-1]:
        out.append(rows[-1])
    return out


def write_csv(path, header, rows, fmt="%.7g"):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        for r in rows:
            w.writerow([fmt % x if isinstance(x, float) else x for x in r])


def read_csv(path):
    """Header and float rows of a CSV written by write_csv."""
    with open(path) as f:
        r = csv.reader(f)
        header = next(r)
        rows = [[float(x) for x in row] for row in r]
    return header, rows


def crossing_time(times, values, level):
    """First time values rises through level (linear interpolation); None if never."""
    for i in range(1, len(values)):
        if values[i - 1] < level <= values[i]:
            f = (level - values[i - 1]) / (values[i] - values[i - 1])
            return times[i - 1] + f * (times[i] - times[i - 1])
    return None


def write_provenance(path, script, args, params, results, wall_s):
    """JSON provenance: tool and version, script, arguments, parameters, results, date.
    wall_s is the simulation loop's wall time (it grows with machine load); process_cpu_s is
    the CPU time of the whole YADE process so far (start-up included).
    Deliberately git-free (the record must not change with the commit it is stored in)."""
    try:
        import yade.config
        version = yade.config.version
    except Exception:  # pragma: no cover - outside YADE
        version = None
    rec = {
        "tool": "YADE (Debian package yade), headless `yade -n -x`",
        "yade_version": version,
        "python": platform.python_version(),
        "script": os.path.basename(script),
        "argv": list(args),
        "params": params,
        "results": results,
        "wall_s": round(wall_s, 2),
        "process_cpu_s": round(time.process_time(), 2),
        "date_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "host": platform.node(),
    }
    with open(path, "w") as f:
        json.dump(rec, f, indent=2, sort_keys=False)
        f.write("\n")
    return rec


def linear_fit(xs, ys):
    """Least-squares slope and intercept of ys against xs."""
    n = float(len(xs))
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    sxy = sum((x - mx) * (y - my) for x, y in zip(xs, ys))
    slope = sxy / sxx
    return slope, my - slope * mx
