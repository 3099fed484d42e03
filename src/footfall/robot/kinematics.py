"""Leg kinematics of a hexapod: body <-> leg frames, inverse and forward kinematics, Jacobian.

Convention (derived in ``docs/frames.md``; it fixes the inconsistent thesis eqs. 5.2-5.9):
the leg frame ``L_i`` has its origin on the coxa axis, ``x`` pointing out along the leg's
mount yaw and ``z`` up. With ``theta1`` the coxa yaw, ``theta2`` the femur elevation above
horizontal and ``theta3`` the tibia angle relative to the femur's extension (negative bends
the foot down)::

    d = L1 + L2 cos(theta2) + L3 cos(theta2 + theta3)     # horizontal reach
    x = d cos(theta1),  y = d sin(theta1)
    z = L2 sin(theta2) + L3 sin(theta2 + theta3)

Inverse kinematics picks the knee-up branch (``theta3 <= 0``), the posture of the thesis'
robot, and assumes the foot is out from the coxa axis (``d > 0``): a foot behind the coxa
axis is reached by turning the coxa half a turn instead. Arrays are vectorised over legs:
a leading axis of length 6 follows spec order.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from footfall.errors import SingularConfigurationError, UnreachableTargetError
from footfall.robot.spec import HexapodSpec

# Joint limits and reach are checked with this slack, so targets computed from FK of an
# in-range pose never fail on rounding [rad] and [m].
_TOLERANCE = 1e-9


class LegKinematics:
    """Kinematics of all six legs of one robot.

    Args:
        spec: The robot description.
    """

    def __init__(self, spec: HexapodSpec) -> None:
        self.spec = spec
        self.names = spec.leg_names
        self.L1 = spec.coxa_length
        self.L2 = spec.femur_length
        self.L3 = spec.tibia_length
        self.mounts_in_body = spec.mount_positions_in_body
        yaws = spec.mount_yaws
        self._cos_yaw = np.cos(yaws)
        self._sin_yaw = np.sin(yaws)
        self.lower = spec.limits.lower
        self.upper = spec.limits.upper
        # Compiled on first use; imported here, not with the module, so a command's --help
        # that names the gaits does not load numba.
        from footfall.robot.reach_kernel import leg_geometry, reached

        self._reach_kernel = reached
        lengths = np.array([self.L1, self.L2, self.L3])
        # The legs as the compiled checks read them: geometry, lengths, lower and upper
        # joint limits (footfall.robot.reach_kernel.reached).
        self.reach_arrays = (
            leg_geometry(self.mounts_in_body, yaws),
            lengths,
            self.lower,
            self.upper,
        )

    # Frames ---------------------------------------------------------------------------
    def body_to_leg(self, points_in_body: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Express one point per leg, given in the body frame, in that leg's frame (eq. A.8).

        Args:
            points_in_body: Shape (6, 3) [m].

        Returns:
            Shape (6, 3) [m].
        """
        p = np.asarray(points_in_body, dtype=np.float64) - self.mounts_in_body
        out = np.empty_like(p)
        out[:, 0] = self._cos_yaw * p[:, 0] + self._sin_yaw * p[:, 1]
        out[:, 1] = -self._sin_yaw * p[:, 0] + self._cos_yaw * p[:, 1]
        out[:, 2] = p[:, 2]
        return out

    def leg_to_body(self, points_in_leg: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Inverse of :meth:`body_to_leg`; shape (6, 3) in and out [m]."""
        p = np.asarray(points_in_leg, dtype=np.float64)
        out = np.empty_like(p)
        out[:, 0] = self._cos_yaw * p[:, 0] - self._sin_yaw * p[:, 1]
        out[:, 1] = self._sin_yaw * p[:, 0] + self._cos_yaw * p[:, 1]
        out[:, 2] = p[:, 2]
        return out + self.mounts_in_body

    def vectors_body_to_leg(self, vectors_in_body: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Rotate free vectors (velocities), shape (6, 3), from the body to each leg frame."""
        v = np.asarray(vectors_in_body, dtype=np.float64)
        out = np.empty_like(v)
        out[:, 0] = self._cos_yaw * v[:, 0] + self._sin_yaw * v[:, 1]
        out[:, 1] = -self._sin_yaw * v[:, 0] + self._cos_yaw * v[:, 1]
        out[:, 2] = v[:, 2]
        return out

    # Kinematics in the leg frame ---------------------------------------------------------
    def forward(self, angles: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Foot positions in each leg frame from joint angles.

        Args:
            angles: ``(theta1, theta2, theta3)`` per leg, shape (..., 3) [rad].

        Returns:
            Foot positions, shape (..., 3) [m].
        """
        q = np.asarray(angles, dtype=np.float64)
        t1, t2, t23 = q[..., 0], q[..., 1], q[..., 1] + q[..., 2]
        d = self.L1 + self.L2 * np.cos(t2) + self.L3 * np.cos(t23)
        z = self.L2 * np.sin(t2) + self.L3 * np.sin(t23)
        return np.stack([d * np.cos(t1), d * np.sin(t1), z], axis=-1)

    def inverse(
        self, feet_in_leg: npt.ArrayLike, check_limits: bool = True
    ) -> npt.NDArray[np.float64]:
        """Joint angles that put each foot on its target (knee-up branch).

        Args:
            feet_in_leg: Foot targets in the leg frames, shape (6, 3) [m].
            check_limits: Also reject solutions outside the joint limits.

        Returns:
            Joint angles, shape (6, 3) [rad].

        Raises:
            UnreachableTargetError: A target is farther than the stretched leg, closer than the
                folded leg, or needs a joint beyond its limits. The error names the first such
                leg and, for reach, by how much the target is out of reach.
        """
        p = np.asarray(feet_in_leg, dtype=np.float64)
        x, y, z = p[..., 0], p[..., 1], p[..., 2]
        d = np.hypot(x, y)
        r = d - self.L1
        c_sq = r * r + z * z
        c = np.sqrt(c_sq)
        max_reach = self.L2 + self.L3
        min_reach = abs(self.L2 - self.L3)
        bad = (c > max_reach + _TOLERANCE) | (c < min_reach - _TOLERANCE)
        if np.any(bad):
            i = int(np.flatnonzero(bad.ravel())[0])
            ci = float(c.ravel()[i])
            if ci > max_reach:
                excess, what = ci - max_reach, "farther than the stretched leg"
            else:
                excess, what = min_reach - ci, "closer than the folded leg"
            raise UnreachableTargetError(
                self.names[i % len(self.names)],
                f"target {np.round(p.reshape(-1, 3)[i], 4).tolist()} m (leg frame) is {what}, "
                f"out of reach by {excess:.4f} m",
                excess,
            )
        t2, t3 = self._femur_tibia(r, z)
        t1 = np.arctan2(y, x)
        angles = np.stack([t1, t2, t3], axis=-1)
        if check_limits:
            self.check_limits(angles)
        return angles

    def reachable(
        self, leg: int, foot_in_body: npt.ArrayLike, margin: float = 0.0
    ) -> bool | npt.NDArray[np.bool_]:
        """Whether one leg reaches foot positions within its joint limits (compiled).

        Args:
            leg: Leg index.
            foot_in_body: Foot target in the body frame, shape (3,), or several, shape
                (..., 3) [m].
            margin: Keep this far inside the workspace boundary [m] (reach) and
                ``margin / L3`` radians inside the joint limits.

        Returns:
            A bool for one target, else a bool array of shape (...).
        """
        ok = self._reached(foot_in_body, int(leg), margin)
        return bool(ok) if np.ndim(ok) == 0 else ok

    def reachable_all(
        self, feet_in_body: npt.ArrayLike, margin: float = 0.0
    ) -> npt.NDArray[np.bool_]:
        """Whether each leg reaches its foot target: :meth:`reachable` for all six at once.

        Args:
            feet_in_body: One target per leg, shape (..., 6, 3) [m].
            margin: As for :meth:`reachable`.

        Returns:
            Shape (..., 6).
        """
        return self._reached(feet_in_body, -1, margin)

    def _reached(self, feet_in_body: npt.ArrayLike, leg: int, margin: float):
        """The compiled reach test of foot positions of one leg (or of all six, ``leg`` -1)."""
        p = np.ascontiguousarray(feet_in_body, dtype=np.float64)
        if leg < 0 and (p.ndim < 2 or p.shape[-2] != len(self.names)):
            raise ValueError(f"feet of all legs need shape (..., 6, 3), got {p.shape}")
        points = p.reshape(-1, 3)
        out = np.empty(len(points), dtype=np.bool_)
        self._reach_kernel(points, leg, *self.reach_arrays, margin, out)
        return out.reshape(p.shape[:-1])

    def _femur_tibia(
        self, r: npt.NDArray[np.float64], z: npt.NDArray[np.float64]
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """Femur and tibia angles (knee-up) [rad] for a foot ``r`` out from the femur joint.

        The foot is ``z`` above the joint [m]; its distance is clipped into the leg's reach.
        """
        cos_knee = (r * r + z * z - self.L2**2 - self.L3**2) / (2.0 * self.L2 * self.L3)
        t3 = -np.arccos(np.clip(cos_knee, -1.0, 1.0))
        t2 = np.arctan2(z, r) - np.arctan2(self.L3 * np.sin(t3), self.L2 + self.L3 * np.cos(t3))
        return np.mod(t2 + np.pi, 2.0 * np.pi) - np.pi, t3  # femur into [-pi, pi)

    def knees_in_body(self, leg: int, feet_in_body: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Where one leg's knee (the femur-tibia joint) is with its foot at each target.

        The knee-up branch, as :meth:`inverse`; a target out of reach puts the knee where
        the stretched or folded leg pointing at it has it.

        Args:
            leg: Leg index.
            feet_in_body: Foot targets in the body frame, shape (..., 3) [m].

        Returns:
            Knee positions in the body frame, shape (..., 3) [m].
        """
        p = np.asarray(feet_in_body, dtype=np.float64) - self.mounts_in_body[leg]
        d = np.hypot(p[..., 0], p[..., 1])
        t2, _ = self._femur_tibia(d - self.L1, p[..., 2])
        out = (self.L1 + self.L2 * np.cos(t2)) / np.maximum(d, _TOLERANCE)
        knees = np.stack([p[..., 0] * out, p[..., 1] * out, self.L2 * np.sin(t2)], axis=-1)
        return knees + self.mounts_in_body[leg]

    def check_limits(self, angles: npt.ArrayLike) -> None:
        """Raise :class:`UnreachableTargetError` if any angle, shape (6, 3), is out of range."""
        q = np.asarray(angles, dtype=np.float64).reshape(-1, 3)
        low = q < self.lower - _TOLERANCE
        high = q > self.upper + _TOLERANCE
        if np.any(low | high):
            i, j = (int(k) for k in np.argwhere(low | high)[0])
            joint = ("coxa", "femur", "tibia")[j]
            bound = self.lower[j] if low[i, j] else self.upper[j]
            raise UnreachableTargetError(
                self.names[i % len(self.names)],
                f"target needs {joint} angle {np.degrees(q[i, j]):.1f} deg, beyond its limit "
                f"{np.degrees(bound):.1f} deg "
                f"(range {np.degrees(self.lower[j]):.1f}..{np.degrees(self.upper[j]):.1f} deg)",
                float("nan"),
            )

    def jacobian(self, angles: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Foot-velocity Jacobian d(foot in leg)/d(angles), derived from :meth:`forward`.

        Args:
            angles: Shape (..., 3) [rad].

        Returns:
            Shape (..., 3, 3): rows x, y, z; columns coxa, femur, tibia [m / rad].
        """
        q = np.asarray(angles, dtype=np.float64)
        t1, t2, t23 = q[..., 0], q[..., 1], q[..., 1] + q[..., 2]
        c1, s1 = np.cos(t1), np.sin(t1)
        d = self.L1 + self.L2 * np.cos(t2) + self.L3 * np.cos(t23)
        dd2 = -self.L2 * np.sin(t2) - self.L3 * np.sin(t23)
        dd3 = -self.L3 * np.sin(t23)
        dz2 = self.L2 * np.cos(t2) + self.L3 * np.cos(t23)
        dz3 = self.L3 * np.cos(t23)
        zero = np.zeros_like(t1)
        return np.stack(
            [
                np.stack([-d * s1, dd2 * c1, dd3 * c1], axis=-1),
                np.stack([d * c1, dd2 * s1, dd3 * s1], axis=-1),
                np.stack([zero, dz2, dz3], axis=-1),
            ],
            axis=-2,
        )

    def joint_rates(
        self, angles: npt.ArrayLike, foot_velocities_in_leg: npt.ArrayLike
    ) -> npt.NDArray[np.float64]:
        """Joint rates that move each foot with the given velocity (replaces thesis eq. 5.9).

        Args:
            angles: Current joint angles, shape (6, 3) [rad].
            foot_velocities_in_leg: Foot velocities in the leg frames, shape (6, 3) [m/s].

        Returns:
            Joint rates, shape (6, 3) [rad/s].

        Raises:
            SingularConfigurationError: A leg is stretched straight (``sin(theta3) ~ 0``) or its
                foot is on the coxa axis, where the Jacobian (determinant
                ``d * L2 * L3 * sin(theta3)``) cannot be inverted.
        """
        q = np.asarray(angles, dtype=np.float64)
        J = self.jacobian(q)
        det = np.linalg.det(J)
        scale = self.L2 * self.L3 * (self.L1 + self.L2 + self.L3)
        singular = np.abs(det) < 1e-6 * scale
        if np.any(singular):
            i = int(np.flatnonzero(singular)[0])
            raise SingularConfigurationError(
                f"leg {self.names[i % len(self.names)]}: joint rates are undefined at angles "
                f"{np.round(np.degrees(q.reshape(-1, 3)[i]), 2).tolist()} deg "
                "(leg stretched straight or foot on the coxa axis)"
            )
        v = np.asarray(foot_velocities_in_leg, dtype=np.float64)
        return np.linalg.solve(J, v[..., None])[..., 0]

    # Body-frame conveniences -------------------------------------------------------------
    def inverse_in_body(
        self, feet_in_body: npt.ArrayLike, check_limits: bool = True
    ) -> npt.NDArray[np.float64]:
        """Joint angles, shape (6, 3) [rad], for foot targets in the body frame [m]."""
        return self.inverse(self.body_to_leg(feet_in_body), check_limits=check_limits)

    def forward_in_body(self, angles: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Foot positions in the body frame, shape (6, 3) [m], from joint angles, shape (6, 3)."""
        return self.leg_to_body(self.forward(angles))
