"""weft_render.curves: Blender's curves as the polylines weft draws (docs/blender.md).

Blender evaluates a Bezier spline with `resolution_u` points per span and
interpolates the point radii along it with the spline's
`radius_interpolation`; hair curves (the Curves object type) use a uniform
Catmull-Rom spline with `resolution` points per span. The functions here do
the same sums in double precision, so the exported polyline is the curve
Blender draws (the add-on's test holds it to the centre and radius of
Blender's own bevelled tube). No bpy here: plain tuples in, lists out.
"""

import math

# Blender's key_curve_position_weights (blenkernel/intern/key.cc): the
# weights of the radii of points i-1, i, i+1, i+2 at parameter t of span i.
_CARDINAL_TENSION = 0.71


def radius_weights(t, interpolation):
    t2, t3 = t * t, t * t * t
    if interpolation == "LINEAR":
        return (0.0, 1.0 - t, t, 0.0)
    if interpolation == "CARDINAL":
        fc = _CARDINAL_TENSION
        return (-fc * t3 + 2 * fc * t2 - fc * t,
                (2 - fc) * t3 + (fc - 3) * t2 + 1,
                (fc - 2) * t3 + (3 - 2 * fc) * t2 + fc * t,
                fc * t3 - fc * t2)
    if interpolation == "BSPLINE":
        return (-t3 / 6 + t2 / 2 - t / 2 + 1 / 6,
                t3 / 2 - t2 + 2 / 3,
                -t3 / 2 + t2 / 2 + t / 2 + 1 / 6,
                t3 / 6)
    if interpolation == "EASE":
        s = 3 * t2 - 2 * t3  # only the span's own two radii, eased
        return (0.0, 1.0 - s, s, 0.0)
    raise ValueError(f"unknown radius interpolation {interpolation!r}")


def _cubic_bezier(p0, p1, p2, p3, t):
    s = 1.0 - t
    return tuple(s * s * s * a + 3 * s * s * t * b + 3 * s * t * t * c + t * t * t * d
                 for a, b, c, d in zip(p0, p1, p2, p3))


def bezier_polyline(points, resolution, cyclic, interpolation):
    """points: [(co, handle_left, handle_right, radius)]. Returns (positions, radii).

    Each span from point i to i+1 gives `resolution` points at t = k / resolution
    (k < resolution); an open spline ends with its last control point.
    """
    n = len(points)
    if n < 2:
        raise ValueError("a Bezier spline needs at least 2 points")
    spans = n if cyclic else n - 1
    positions, radii = [], []

    def radius_at(i):
        if cyclic:
            return points[i % n][3]
        return points[min(max(i, 0), n - 1)][3]

    for i in range(spans):
        a, b = points[i], points[(i + 1) % n]
        for k in range(resolution):
            t = k / resolution
            positions.append(_cubic_bezier(a[0], a[2], b[1], b[0], t))
            w = radius_weights(t, interpolation)
            radii.append(sum(wj * radius_at(i - 1 + j) for j, wj in enumerate(w)))
    if not cyclic:
        positions.append(tuple(points[-1][0]))
        radii.append(points[-1][3])
    return positions, radii


def nurbs_knots(count, order, cyclic, endpoint, bezier):
    """Blender's knot vector of a NURBS spline (blenkernel curve.cc, calcknots)."""
    repeat_inner = order - 1 if bezier else 1
    head = (order - (1 if cyclic else 0)) if endpoint else (min(2, repeat_inner) if bezier else 1)
    tail = 2 * order - 1 if cyclic else (order if endpoint else 0)
    total = count + order + (order - 1 if cyclic else 0)
    knots = [0.0] * total
    offset = 1 if endpoint and cyclic else 0
    current, r = 0.0, head
    if offset:
        current = 1.0
    for i in range(offset, total - tail):
        knots[i] = current
        r -= 1
        if r == 0:
            current += 1.0
            r = repeat_inner
    for i in range(tail):
        knots[total - tail + i] = current + (knots[i] - knots[0])
    return knots


def _nurbs_basis(u, order, knots, count):
    """The B-spline basis functions N_i,order(u), i < count (Cox-de Boor); at the
    end of the domain the last non-empty span holds u."""
    n = len(knots) - 1
    span = None
    for i in range(n):
        if knots[i] <= u < knots[i + 1]:
            span = i
    if span is None:  # u at the very end: the last span of positive length
        span = max(i for i in range(n) if knots[i] < knots[i + 1])
    basis = [1.0 if i == span else 0.0 for i in range(n)]
    for k in range(2, order + 1):
        for i in range(n - k + 1):
            left = right = 0.0
            if knots[i + k - 1] != knots[i]:
                left = (u - knots[i]) / (knots[i + k - 1] - knots[i]) * basis[i]
            if knots[i + k] != knots[i + 1]:
                right = (knots[i + k] - u) / (knots[i + k] - knots[i + 1]) * basis[i + 1]
            basis[i] = left + right
    return basis[:count]


def nurbs_polyline(points, order, resolution, cyclic, endpoint, bezier):
    """points: [(x, y, z, weight, radius)]. Blender's evaluation of a NURBS
    spline (BKE_nurb_makeCurve): resolution x segments points at equal steps
    of the knot parameter, the rational basis weighting positions and radii."""
    n = len(points)
    order = min(order, n)
    if n < 2 or order < 2:
        raise ValueError("a NURBS spline needs at least 2 points and order 2")
    extra = order - 1 if cyclic else 0
    knots = nurbs_knots(n, order, cyclic, endpoint, bezier)
    wrapped = [points[i % n] for i in range(n + extra)]
    total = resolution * (n if cyclic else n - 1)
    u_start = knots[order - 1]
    u_end = knots[n + order - 1] if cyclic else knots[n]
    step = (u_end - u_start) / (total - (0 if cyclic else 1))
    positions, radii = [], []
    for k in range(total):
        u = u_start + k * step
        basis = _nurbs_basis(u, order, knots, len(wrapped))
        weights = [b * p[3] for b, p in zip(basis, wrapped)]
        norm = sum(weights)
        positions.append(tuple(sum(w * p[j] for w, p in zip(weights, wrapped)) / norm
                               for j in range(3)))
        radii.append(sum(w * p[4] for w, p in zip(weights, wrapped)) / norm)
    return positions, radii


def _catmull_rom(p0, p1, p2, p3, t):
    # Blender's curves::catmull_rom::calculate_basis (uniform, tension 1/2).
    t2, t3 = t * t, t * t * t
    w = (0.5 * (-t3 + 2 * t2 - t), 0.5 * (3 * t3 - 5 * t2 + 2),
         0.5 * (-3 * t3 + 4 * t2 + t), 0.5 * (t3 - t2))
    return tuple(w[0] * a + w[1] * b + w[2] * c + w[3] * d for a, b, c, d in zip(p0, p1, p2, p3))


def catmull_rom_polyline(points, radii, resolution, cyclic):
    """A uniform Catmull-Rom curve through `points` (the end points doubled on an
    open curve), `resolution` points per span; radii interpolated alike."""
    n = len(points)
    if n < 2:
        raise ValueError("a curve needs at least 2 points")
    spans = n if cyclic else n - 1

    def at(values, i):
        return values[i % n] if cyclic else values[min(max(i, 0), n - 1)]

    out_p, out_r = [], []
    for i in range(spans):
        for k in range(resolution):
            t = k / resolution
            out_p.append(_catmull_rom(*(at(points, i + j) for j in range(-1, 3)), t))
            out_r.append(_catmull_rom(*((at(radii, i + j),) for j in range(-1, 3)), t)[0])
    if not cyclic:
        out_p.append(tuple(points[-1]))
        out_r.append(radii[-1])
    return out_p, out_r


def mean_scale(matrix3):
    """The length scale of a 3 x 3 linear map: |det|^(1/3) (exact for uniform scales)."""
    m = matrix3
    det = (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))
    return abs(det) ** (1.0 / 3.0)


def write_curves_txt(path, curves):
    """curves: [(positions, radii, closed)] in weft's world. The `.txt` format of
    docs/curves.md, `x y z radius` per point (repr: exact doubles)."""
    lines = ["# weft curves exported from Blender (x y z radius, weft world: +y up)"]
    for positions, radii, closed in curves:
        lines.append("")
        if closed:
            lines.append("# closed")
        for p, r in zip(positions, radii):
            if not (math.isfinite(r) and r > 0):
                raise ValueError(f"radius {r} is not > 0")
            lines.append(f"{p[0]!r} {p[1]!r} {p[2]!r} {r!r}")
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")
