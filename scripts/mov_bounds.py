#!/usr/bin/env python3
"""Lower bounds on a single part's outside volume OV, for the features that keep MOV high.

OV_i = vol(V_i minus S) / vol(S_i), with V_i a volume that holds the part S_i. Space inside
the solid costs nothing, so V_i may reach freely into the rest of the solid. Two features
that every shared mesh of animals, people and furniture has at the scale of a part:

1. A flat end: the part is the last piece (length L, radius r) of a cylinder ending in a flat
   disk (a hoof, the foot of a chair leg, a finger cut square). A coaxial ellipsoid (centre
   on the axis, semi-axes A along it and b across) that holds the piece must reach radius
   r over the whole piece; beyond the flat end, and beside the cylinder, it is outside.
2. A pointed tip: the part is the tip (length l) of a cone (an ear, a tail, a horn).
   Coaxial ellipsoids and boxes with an axis along the cone's must hold the apex.

The script minimises OV over those volumes numerically (stdlib only, midpoint quadrature and a
grid search), and prints the minima next to the closed forms:

- flat end, ellipsoid:   min OV = 1/2        (at u = 1/2: centred mid-piece, A = L)
- pointed tip, ellipsoid: OV = A / (2A - 1) > 1/2 for A in units of the tip's length,
                          approaching 1/2 only as the ellipsoid becomes infinitely long
- pointed tip, box with an axis along the cone's: OV >= 12 / pi - 1 = 2.82

So a part with a flat end has OV >= 0.5 with an ellipsoid, and a part with a pointed tip has
OV > 0.5 with an ellipsoid and OV > 2.8 with a box (coaxial volumes; tilting them away from
the feature's axis of symmetry only makes them stick out more in every case we tried): MOV <
0.5 is out of reach for both kinds of volume on a mesh with a pointed tip, whatever the
partition, the sampling or the fit. All of this is before the extra slack of holding the mesh
surface, which lies up to half a cell beyond the outermost cell centres.

    python3 scripts/mov_bounds.py
"""
import math


def flat_end_ellipsoid(steps=2000):
    """min over u of OV for the coaxial ellipsoid of a flat-ended piece.

    With the ellipsoid's axial coordinate t in [-1, 1] (units of A) and its radius b at the
    centre, it reaches the cylinder's radius r = b sqrt(1 - u^2) for |t| <= u; the piece fills
    t in [-u, u] (its length is 2uA: the best piece is as long as the ellipsoid allows) and its
    flat end is at t = u. Beside the piece the ellipsoid bulges out of the cylinder; beyond the
    end everything is outside; behind the piece (t < -u) it is thinner than the cylinder and
    inside. In units of pi A b^2:
      outside = int_{-u}^{u} ((1 - t^2) - (1 - u^2)) dt + int_u^1 (1 - t^2) dt
      piece   = 2u (1 - u^2)
    """
    best = (math.inf, None)
    for i in range(1, steps):
        u = i / steps
        bulge = 4.0 / 3.0 * u**3
        cap = 2.0 / 3.0 - u + u**3 / 3.0
        piece = 2.0 * u * (1.0 - u * u)
        ov = (bulge + cap) / piece
        if ov < best[0]:
            best = (ov, u)
    return best


def cone_tip_ellipsoid(a, n=20000):
    """OV of the coaxial ellipsoid with its end at the apex of a 45-degree cone (any cone is
    an affine image of it, and affine maps keep volume ratios), semi-axis `a` along the axis,
    tight on the circle at the tip's end (s = 1, radius 1). The tip is s in [0, 1], volume
    pi / 3; the ellipsoid's radius^2 at s is b^2 (1 - ((s - a) / a)^2) = b^2 s (2a - s) / a^2.
    Outside: wherever that exceeds the cone's s^2 (beyond s = 1 the cone is free space only
    where the ellipsoid is inside it)."""
    b2 = a * a / (2.0 * a - 1.0)  # tight at s = 1: b^2 (2a - 1) / a^2 = 1
    top = 2.0 * a
    h = top / n
    out = 0.0
    for i in range(n):
        s = (i + 0.5) * h
        r2 = b2 * s * (2.0 * a - s) / (a * a)
        out += max(0.0, r2 - s * s) * h
    return out / (1.0 / 3.0)


def cone_tip_box():
    """A box with an axis along the cone's, holding its tip (apex to depth l, radius l tan(alpha) at its end) is at least
    2 l tan(alpha) wide across the axis over the whole depth l, so what it holds beside the
    cone there is at least int_0^l (4 rho^2 - pi tan^2(alpha) z^2) dz with rho = l tan(alpha):
    (4 - pi / 3) l^3 tan^2(alpha) against the tip's pi l^3 tan^2(alpha) / 3."""
    return (4.0 - math.pi / 3.0) / (math.pi / 3.0)


def main():
    ov, u = flat_end_ellipsoid()
    print(f"flat end, coaxial ellipsoid: min OV = {ov:.4f} at u = {u:.3f} (closed form 0.5 at u = 0.5)")
    print("pointed tip, coaxial ellipsoid with its end at the apex (a in units of the tip's length):")
    for a in [1, 2, 5, 10, 30, 100]:
        num = cone_tip_ellipsoid(a)
        print(f"  a = {a:4d}: OV = {num:.4f} (closed form a / (2a - 1) = {a / (2 * a - 1):.4f})")
    print(f"pointed tip, box along the axis: OV >= {cone_tip_box():.4f} (12 / pi - 1)")


if __name__ == "__main__":
    main()
