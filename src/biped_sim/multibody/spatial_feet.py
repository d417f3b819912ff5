"""The spatial formulation's feet against the ground: the plane y = 0 or a ground profile (compiled with numba).

A foot is a disc of radius R (a circle in its body around its local axis), a sphere (axis 0), a torus (a disc
with a tube) or an ellipsoid (a quadric). :func:`foot_support` is its point most against a direction u (the
lowest point when u = (0, -1, 0)): a disc's point R d, d the unit direction in its plane closest to u; a sphere's
R u; a torus's disc point moved by the tube radius along u; an ellipsoid's M u / sqrt(u.M u), M = A Q A^T.

On the flat ground the foot touches at its lowest point (the kernels of ``FlatGround``, unchanged). A ground
profile (:mod:`biped_sim.contact.ground`) varies along the slope (x) and is constant across it (z): a point of
the foot is under the ground when its (x, y) is under the planar profile, so the foot's contact with the
profile is that of its outline, the foot projected onto the x-y plane, with the planar profile. A sphere's or
a point's outline, and a disc's or torus's whose axis is along z (a planar walker lifted into space), is a
circle: the planar profile kernels (``ground_contacts``: segments, convex corners, a valley's corner
subtracted) apply to it exactly. Any other outline (a ring turned out of the sagittal plane, an ellipsoid) is
replaced by its osculating circle at its support point along the ground's normal n under it: the circle of
radius rho (:func:`outline_radius`, the outline's radius of curvature there) through that point, centred
rho along n from it. On a straight stretch of ground this is exact (the support point is the contact point);
across a kink or a step's edge the outline is approximated to second order in its distance from that point
(its curvature's change is neglected), and the normal n is that of the deepest feature of the circle found
first about the lowest point (n = (0, 1)). Each feature's force F_N n + F_T acts at its contact point, the
circle's point against its normal at the support point's z; friction acts in the feature's tangent plane (the
profile's tangent t = (n_y, -n_x, 0) and z) along the slip of the material point there, as on flat ground.
"""

from __future__ import annotations

import math

import numpy as np

from biped_sim.contact.friction import (
    LUGRE,
    SPIN_RADIUS,
    friction_force,
    lugre_bristle_rate,
    lugre_friction,
    spin_friction_torque,
)
from biped_sim.contact.ground import FlatGround, ProfileGround, ground_contact, ground_contacts, ground_window
from biped_sim.contact.registry import by_type
from biped_sim.contact.response import (
    FRICTION_MODEL,
    IMPACT_FLOOR,
    NORMAL_MODEL,
    arc_energy,
    is_loaded,
    normal_response,
)
from biped_sim.contact.response import stored_energy as spring_energy
from biped_sim.kernel import kernel
from biped_sim.multibody.euler_parameters import (
    b_mul,
    b_tmul,
    dot3,
    e_mul,
    e_tmul,
    inertia_mul,
    parameters,
    position,
    rotate,
    rotate_t,
    vec3,
)
from biped_sim.multibody.spatial import SpatialSystem

DOWN = (0.0, -1.0, 0.0)  # against the flat ground's normal
EX, EY = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)


@kernel
def foot_support(p: tuple, system: SpatialSystem, i: int, u: tuple) -> tuple[tuple, tuple, tuple]:
    """Foot i's point P most along the unit direction u on a body turned by the parameters p: (c, b, s') with
    c = A c' its centre and b = P - c from there (slope frame, P = r + c + b), and s' its body-frame lever,
    A s' = c + b (A = rotate(p, .): p.p times the rotation, so that the lever holds off the unit sphere too).

    A disc (axis a): R d, d = (u - (u.a) a) / sqrt(1 - (u.a)^2), the unit direction in its plane closest to u; a
    sphere (axis 0): R u from the centre; a torus: its disc's point moved by the tube radius along u (the tube's
    section there is a circle in the plane of d and u, farthest along u straight from its centre); an ellipsoid
    (quadric Q, body frame): A Q m / sqrt(m.Q m) / p.p, m = A^T u the direction in the body frame.
    """
    sc = vec3(system.foot_center, i, 0)
    centre = rotate(p, sc)
    pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]
    if system.foot_quadric[i, 0, 0] > 0.0:
        m = rotate_t(p, u)
        qm = inertia_mul(system.foot_quadric, i, m)
        k = 1.0 / (pp * math.sqrt(dot3(m, qm)))
        lever = (k * qm[0], k * qm[1], k * qm[2])
        return centre, rotate(p, lever), (sc[0] + lever[0], sc[1] + lever[1], sc[2] + lever[2])
    radius = system.foot_radius[i]
    axis = vec3(system.foot_axis, i, 0)
    d = u
    if dot3(axis, axis) > 0.0:
        a = rotate(p, axis)
        inv = 1.0 / math.sqrt(dot3(a, a))
        a0, a1, a2 = a[0] * inv, a[1] * inv, a[2] * inv
        ua = u[0] * a0 + u[1] * a1 + u[2] * a2
        norm = math.sqrt(max(1.0 - ua * ua, 1e-300))
        d = ((u[0] - ua * a0) / norm, (u[1] - ua * a1) / norm, (u[2] - ua * a2) / norm)
    local_d = rotate_t(p, d)
    scale = radius / (pp * pp)
    s = (sc[0] + scale * local_d[0], sc[1] + scale * local_d[1], sc[2] + scale * local_d[2])
    bottom = (radius * d[0], radius * d[1], radius * d[2])
    tube = system.foot_tube[i]
    if tube > 0.0:
        local_u = rotate_t(p, u)
        k = tube / (pp * pp)
        s = (s[0] + k * local_u[0], s[1] + k * local_u[1], s[2] + k * local_u[2])
        bottom = (bottom[0] + tube * u[0], bottom[1] + tube * u[1], bottom[2] + tube * u[2])
    return centre, bottom, s


@kernel
def foot_bottom(p: tuple, system: SpatialSystem, i: int) -> tuple[tuple, tuple, tuple]:
    """Foot i's lowest point against the ground plane y = 0: :func:`foot_support` along (0, -1, 0)."""
    return foot_support(p, system, i, DOWN)


@kernel
def outline_radius(p: tuple, system: SpatialSystem, i: int, nx: float, ny: float) -> float:
    """Radius of curvature of foot i's outline in the x-y plane at its support point against n = (nx, ny, 0).

    The outline of a convex foot whose support function is sqrt(u.M u) (an ellipsoid: M = A Q A^T; a disc:
    R^2 (I - a a^T)) is the ellipse of M's x-y block M2, of radius of curvature det(M2) / (n.M2 n)^(3/2) along n:
    R a_z^2 / (1 - (n.a)^2)^(3/2) for a disc of unit axis a (R when a is z), plus a torus's tube; a sphere's R, a
    point's 0.
    """
    pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]
    if system.foot_quadric[i, 0, 0] > 0.0:
        wx, wy = rotate_t(p, EX), rotate_t(p, EY)  # p.p A^T e_x, p.p A^T e_y
        qx, qy = inertia_mul(system.foot_quadric, i, wx), inertia_mul(system.foot_quadric, i, wy)
        mxx, mxy, myy = dot3(wx, qx) / (pp * pp), dot3(wx, qy) / (pp * pp), dot3(wy, qy) / (pp * pp)
        along = nx * nx * mxx + 2.0 * nx * ny * mxy + ny * ny * myy
        return (mxx * myy - mxy * mxy) / (along * math.sqrt(along))
    radius = system.foot_radius[i]
    axis = vec3(system.foot_axis, i, 0)
    if dot3(axis, axis) > 0.0:
        a = rotate(p, axis)
        aa = dot3(a, a)
        na = (nx * a[0] + ny * a[1]) ** 2 / aa
        across = max(1.0 - na, 1e-300)
        radius *= (a[2] * a[2] / aa) / (across * math.sqrt(across))
    return radius + system.foot_tube[i]


@kernel
def _osculating(r: tuple, p: tuple, system: SpatialSystem, i: int, nx: float, ny: float) -> tuple[float, ...]:
    """(C_x, C_y, rho, P_z): foot i's osculating outline circle at its support point P against n = (nx, ny, 0)."""
    centre, bottom, _ = foot_support(p, system, i, (-nx, -ny, 0.0))
    rho = outline_radius(p, system, i, nx, ny)
    px, py, pz = r[0] + centre[0] + bottom[0], r[1] + centre[1] + bottom[1], r[2] + centre[2] + bottom[2]
    return px + rho * nx, py + rho * ny, rho, pz


@kernel(reference_counts=False)
def outline_circle(y: np.ndarray, system: SpatialSystem, i: int, ground: ProfileGround) -> tuple[float, ...]:
    """Foot i's outline as a circle against the profile: (C_x, C_y, rho, P_z), the osculating circle at its
    support point P along the normal of the deepest feature of the circle found about its lowest point."""
    b = system.foot_body[i]
    r, p = position(y, b), parameters(y, b)
    cx, cy, rho, _ = _osculating(r, p, system, i, 0.0, 1.0)
    _, _, _, nx, ny = ground_contact(cx, cy, rho, ground.vertices, ground.ends)
    return _osculating(r, p, system, i, nx, ny)


@kernel(reference_counts=False)
def feature_motion(
    y: np.ndarray, system: SpatialSystem, i: int, point: tuple, nx: float, ny: float
) -> tuple[float, float, float, float, float, float]:
    """(delta_dot, slip_t, slip_z, s0, s1, s2) of foot i's material point at ``point`` (slope frame) under the
    feature of normal n = (nx, ny, 0): -v_P.n, v_P.t with t = (n_y, -n_x, 0), v_P.z and its body-frame lever s'."""
    nb = system.body_mass.shape[0]
    b = system.foot_body[i]
    r = position(y, b)
    p = parameters(y, b)
    pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3]
    lever = rotate_t(p, (point[0] - r[0], point[1] - r[1], point[2] - r[2]))
    s = (lever[0] / (pp * pp), lever[1] / (pp * pp), lever[2] / (pp * pp))
    v = position(y, nb + b)
    w = b_mul(p, s, parameters(y, nb + b))
    vx, vy, vz = v[0] + w[0], v[1] + w[1], v[2] + w[2]
    return -(vx * nx + vy * ny), vx * ny - vy * nx, vz, s[0], s[1], s[2]


@kernel(reference_counts=False)
def _flat_kinematics(y: np.ndarray, system: SpatialSystem, i: int, ground: FlatGround) -> tuple[float, ...]:
    nb = system.body_mass.shape[0]
    b = system.foot_body[i]
    r = position(y, b)
    p = parameters(y, b)
    centre, bottom, s = foot_bottom(p, system, i)
    px = r[0] + centre[0] + bottom[0]
    py = r[1] + centre[1] + bottom[1]
    pz = r[2] + centre[2] + bottom[2]
    v = position(y, nb + b)
    w = b_mul(p, s, parameters(y, nb + b))
    return -py, -(v[1] + w[1]), v[0] + w[0], v[2] + w[2], px, pz, s[0], s[1], s[2]


@kernel(reference_counts=False)
def _profile_kinematics(y: np.ndarray, system: SpatialSystem, i: int, ground: ProfileGround) -> tuple[float, ...]:
    cx, cy, rho, pz = outline_circle(y, system, i, ground)
    delta, px, py, nx, ny = ground_contact(cx, cy, rho, ground.vertices, ground.ends)
    delta_dot, slip_t, slip_z, s0, s1, s2 = feature_motion(y, system, i, (px, py, pz), nx, ny)
    return delta, delta_dot, slip_t, slip_z, px, pz, s0, s1, s2


foot_geometry = by_type("foot_geometry", "ground", {FlatGround: _flat_kinematics, ProfileGround: _profile_kinematics})
foot_geometry.__doc__ = """Foot i against ``ground``.

Returns (delta, delta_dot, slip_t, slip_z, x_contact, z_contact, s0, s1, s2): the penetration of its contact
point P (on the flat ground its lowest point, -P_y; on a profile its outline's deepest feature), the approach
velocity -v_P.n, the slip velocity (v_P.t, v_P.z) of the material point at P (t = (1, 0, 0) on the flat ground),
P's place along the slope and across it, and s' = A^-1 (P - r), the body-frame lever of the contact force (its
velocity is rdot + B(p, s') pdot, so the contact power and the generalized force B^T F agree exactly).
"""


@kernel(reference_counts=False)
def foot_kinematics(y: np.ndarray, system: SpatialSystem, i: int) -> tuple[float, ...]:
    """:func:`foot_geometry` of foot i against the system's ground."""
    return foot_geometry(y, system, i, system.ground)


@kernel
def spin_load(p: tuple, pd: tuple, n: tuple, model: int, f_n: float, fpar: np.ndarray) -> tuple[float, ...]:
    """(Q_0, Q_1, Q_2, Q_3, P): the spin friction torque M_n n about the unit contact normal n as the generalized
    force 2 E(p)^T (M_n n) on the Euler parameters, and its dissipation rate P = -M_n w_n >= 0, with w_n = n.omega,
    omega = 2 E(p) pdot, M_n = :func:`~biped_sim.contact.friction.spin_friction_torque` (Q.pdot = M_n w_n exactly,
    so the energy audit closes with P)."""
    w_n = 2.0 * dot3(n, e_mul(p, pd))
    m_n = spin_friction_torque(model, w_n, f_n, fpar)
    q = e_tmul(p, n)
    return 2.0 * m_n * q[0], 2.0 * m_n * q[1], 2.0 * m_n * q[2], 2.0 * m_n * q[3], -m_n * w_n


@kernel(reference_counts=False)
def _flat_load(y: np.ndarray, system: SpatialSystem, modes: np.ndarray, i: int, ground: FlatGround) -> tuple:
    delta, delta_dot, vx, vz, _, _, s0, s1, s2 = _flat_kinematics(y, system, i, ground)
    f_n = f_x = f_z = zdx = zdz = p_normal = p_friction = 0.0  # one return: numba then elides reference counting
    spin = (0.0, 0.0, 0.0, 0.0, 0.0)
    if is_loaded(modes, i, delta):
        npar, floor = system.normal_params, system.limits[IMPACT_FLOOR]
        f_n, p_normal = normal_response(system.switches[NORMAL_MODEL], npar, floor, modes, i, delta, delta_dot)
        fpar = system.friction_params
        speed = math.sqrt(vx * vx + vz * vz)
        if system.switches[FRICTION_MODEL] == LUGRE:
            k = 14 * system.body_mass.shape[0] + 2 * i
            zx, zz = y[k], y[k + 1]
            zdx = lugre_bristle_rate(speed, zx, fpar) - speed + vx
            zdz = lugre_bristle_rate(speed, zz, fpar) - speed + vz
            f_x = lugre_friction(vx, zx, zdx, f_n, fpar)
            f_z = lugre_friction(vz, zz, zdz, f_n, fpar)
        elif speed > 0.0:
            f_t = friction_force(system.switches[FRICTION_MODEL], speed, f_n, fpar)
            f_x = f_t * (vx / speed)
            f_z = f_t * (vz / speed)
        p_friction = -(f_x * vx + f_z * vz)
        if fpar[SPIN_RADIUS] > 0.0:
            b = system.foot_body[i]
            nb = system.body_mass.shape[0]
            spin = spin_load(parameters(y, b), parameters(y, nb + b), EY, system.switches[FRICTION_MODEL], f_n, fpar)
            p_friction += spin[4]
    q = b_tmul(parameters(y, system.foot_body[i]), (s0, s1, s2), (f_x, f_n, f_z))
    q0, q1, q2, q3 = q[0] + spin[0], q[1] + spin[1], q[2] + spin[2], q[3] + spin[3]
    return f_x, f_n, f_z, q0, q1, q2, q3, zdx, zdz, p_normal, p_friction, f_n, f_x, f_z


@kernel(reference_counts=False)
def _profile_load(y: np.ndarray, system: SpatialSystem, modes: np.ndarray, i: int, ground: ProfileGround) -> tuple:
    cx, cy, rho, pz = outline_circle(y, system, i, ground)
    p = parameters(y, system.foot_body[i])
    pd = parameters(y, system.body_mass.shape[0] + system.foot_body[i])
    f_x = f_y = f_z = q0 = q1 = q2 = q3 = p_normal = p_friction = f_normal = f_tangent = 0.0
    first, count = ground_window(cx, rho, ground.vertices)
    for f in range(count):
        depth, px, py, nx, ny, sign = ground_contacts(cx, cy, rho, ground.vertices, ground.ends, first, count, f)
        if not is_loaded(modes, i, depth):
            continue
        depth_dot, v_t, v_z, s0, s1, s2 = feature_motion(y, system, i, (px, py, pz), nx, ny)
        f_n, p_n = normal_response(
            system.switches[NORMAL_MODEL], system.normal_params, system.limits[IMPACT_FLOOR], modes, i, depth, depth_dot
        )
        speed = math.sqrt(v_t * v_t + v_z * v_z)
        f_t = friction_force(system.switches[FRICTION_MODEL], speed, f_n, system.friction_params) / max(speed, 1e-300)
        if system.friction_params[SPIN_RADIUS] > 0.0:
            spin = spin_load(p, pd, (nx, ny, 0.0), system.switches[FRICTION_MODEL], f_n, system.friction_params)
            q0, q1, q2, q3 = q0 + sign * spin[0], q1 + sign * spin[1], q2 + sign * spin[2], q3 + sign * spin[3]
            p_friction += sign * spin[4]
        f_n, f_t, p_n = sign * f_n, sign * f_t, sign * p_n  # a valley's corner term is subtracted
        force = (f_n * nx + f_t * v_t * ny, f_n * ny - f_t * v_t * nx, f_t * v_z)
        q = b_tmul(p, (s0, s1, s2), force)
        f_x, f_y, f_z = f_x + force[0], f_y + force[1], f_z + force[2]
        q0, q1, q2, q3 = q0 + q[0], q1 + q[1], q2 + q[2], q3 + q[3]
        p_normal += p_n
        p_friction -= f_t * speed * speed
        f_normal += f_n
        f_tangent += f_t * v_t
    return f_x, f_y, f_z, q0, q1, q2, q3, 0.0, 0.0, p_normal, p_friction, f_normal, f_tangent, f_z


foot_load = by_type("foot_load", "ground", {FlatGround: _flat_load, ProfileGround: _profile_load})
foot_load.__doc__ = """Contact forces on foot i against ``ground`` and their dissipation rates.

Returns (F_x, F_y, F_z, Q_0, Q_1, Q_2, Q_3, zdot_x, zdot_z, P_normal, P_friction, F_N, F_T, F_lateral): the force
in the slope frame and the generalized force B(p, s')^T F of the body's Euler parameters, summed over the contact
features (one on the flat ground, the lowest point's) with the spin friction torque about each feature's normal
when ``friction.spin_radius`` > 0 (:func:`spin_load`), the LuGre bristle rates (flat ground only: profiles refuse
LuGre), the powers lost in the normal damping (:func:`~biped_sim.contact.response.normal_response`) and in
friction -F_T.v_t (and -M_n w_n), and the summed normal force and friction force along the slope's tangent and
across it. The friction laws act along the slip direction, F_T = F(|v|) v / |v|, exactly 0 at |v| = 0 (every law
is odd in v and vanishes at 0, so this is continuous); LuGre carries a 2-vector bristle state per foot,
zdot = v - sigma0 |v| z / g(|v|), written with the scalar law as zdot_k = rate(|v|, z_k) - |v| + v_k,
F_k = lugre_friction(v_k, z_k, zdot_k, F_N).
"""


@kernel
def _flat_energy(y: np.ndarray, system: SpatialSystem, modes: np.ndarray, i: int, ground: FlatGround) -> float:
    return spring_energy(system, modes, i, _flat_kinematics(y, system, i, ground)[0])


@kernel
def _profile_energy(y: np.ndarray, system: SpatialSystem, modes: np.ndarray, i: int, ground: ProfileGround) -> float:
    cx, cy, rho, _ = outline_circle(y, system, i, ground)
    return arc_energy(system, modes, i, cx, cy, rho, ground)  # the outline circle's, as a planar foot arc's


foot_energy = by_type("foot_energy", "ground", {FlatGround: _flat_energy, ProfileGround: _profile_energy})
foot_energy.__doc__ = """Energy in foot i's contact springs against ``ground``, summed over its contact features."""
