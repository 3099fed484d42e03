"""Long depth sequences with exact ground truth: a hand-held Kinect in a cluttered room.

The shared real sequences are short (37 and 5 frames): too short for drift to show. This
renders longer ones in MuJoCo, in the TUM layout ``footfall odometry`` and the odometry
benchmark read: a room (floor, four walls, a ceiling) with furniture-sized boxes, cylinders,
spheres and capsules at random places, seen by a 640 x 480 camera (fx = fy = 525) carried
along a smooth random path at 30 Hz (walking speed, head-like turns), its depth degraded as a
Kinect's is: the axial noise of Nguyen et al. (``footfall.sensing.noise.KINECT``), disparity
quantised to an eighth of a pixel (7.5 cm baseline, 580 px focal length), no reading beyond
4.5 m and at 1 % of pixels, and the true camera-to-world poses in ``groundtruth.txt``.

Each seed is another room and another path: ``uv run python benchmarks/rgbd_scenes.py OUT
--seed S --frames N``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import mujoco
import numpy as np
from PIL import Image
from scipy.spatial.transform import Rotation

from footfall.datasets.tum import TUM_DEPTH_SCALE
from footfall.sensing.noise import KINECT

WIDTH, HEIGHT, FOCAL_PX = 640, 480, 525.0
INTRINSICS = (FOCAL_PX, FOCAL_PX, 0.5 * (WIDTH - 1), 0.5 * (HEIGHT - 1))
RATE_HZ = 30.0
ROOM_M = (6.0, 5.0, 2.8)  # x, y, z extent; the floor at z = 0, centred on x = y = 0
KINECT_BASELINE_M, KINECT_FOCAL_PX, DISPARITY_STEP_PX = 0.075, 580.0, 0.125
MAX_RANGE_M = 4.5


def room_xml(rng: np.random.Generator, clutter: int) -> str:
    """MJCF of the room, its clutter and a mocap body carrying the camera."""
    lx, ly, lz = (0.5 * v for v in ROOM_M)
    walls = [
        ("0 0 -0.05", f"{lx} {ly} 0.05"),
        ("0 0 " + str(2 * lz + 0.05), f"{lx} {ly} 0.05"),
        (f"{lx + 0.05} 0 {lz}", f"0.05 {ly} {lz}"),
        (f"{-lx - 0.05} 0 {lz}", f"0.05 {ly} {lz}"),
        (f"0 {ly + 0.05} {lz}", f"{lx} 0.05 {lz}"),
        (f"0 {-ly - 0.05} {lz}", f"{lx} 0.05 {lz}"),
    ]
    geoms = [f'<geom type="box" pos="{p}" size="{s}"/>' for p, s in walls]
    for _ in range(clutter):
        kind = rng.choice(["box", "box", "cylinder", "sphere", "capsule"])
        # Near the walls more than in the middle, where the camera walks.
        x = rng.uniform(-lx + 0.3, lx - 0.3) * (1 if rng.random() < 0.5 else 0.6)
        y = rng.uniform(-ly + 0.3, ly - 0.3)
        if abs(x) < 1.5 and abs(y) < 1.2:
            y = np.sign(y or 1.0) * rng.uniform(1.2, ly - 0.3)
        size = rng.uniform(0.08, 0.5, 3)
        z = size[2] if rng.random() < 0.7 else rng.uniform(0.3, 2.0)
        yaw = rng.uniform(0, 180)
        geoms.append(
            f'<geom type="{kind}" pos="{x:.3f} {y:.3f} {z:.3f}" euler="0 0 {yaw:.1f}" '
            f'size="{size[0]:.3f} {size[1]:.3f} {size[2]:.3f}"/>'
        )
    fovy = np.degrees(2 * np.arctan(0.5 * HEIGHT / FOCAL_PX))
    return f"""<mujoco>
  <visual><global offwidth="{WIDTH}" offheight="{HEIGHT}"/><map znear="0.05" zfar="20"/></visual>
  <worldbody>
    {"".join(geoms)}
    <body name="carrier" mocap="true">
      <camera name="depth" fovy="{fovy:.6f}"/>
    </body>
  </worldbody>
</mujoco>"""


def hand_held_path(rng: np.random.Generator, frames: int) -> list[np.ndarray]:
    """Camera-to-world poses (optical frame) along a smooth random path through the room."""
    t = np.arange(frames) / RATE_HZ
    # A loop round the room's middle, with sums of slow sinusoids on top.
    period = rng.uniform(20.0, 40.0)
    phase = rng.uniform(0, 2 * np.pi)
    position = np.stack(
        [
            1.1 * np.cos(2 * np.pi * t / period + phase),
            0.8 * np.sin(2 * np.pi * t / period + phase),
            1.3 + 0.0 * t,
        ],
        axis=1,
    )
    angles = np.zeros((frames, 3))  # yaw, pitch, roll
    for axis, amplitude in ((0, 0.6), (1, 0.25), (2, 0.08)):
        for _ in range(3):
            f, p = rng.uniform(0.03, 0.25), rng.uniform(0, 2 * np.pi)
            angles[:, axis] += amplitude / 3 * np.sin(2 * np.pi * f * t + p)
    for k in range(3):
        f, p = rng.uniform(0.1, 0.4), rng.uniform(0, 2 * np.pi)
        position[:, k] += 0.1 * np.sin(2 * np.pi * f * t + p)
    outward = np.arctan2(position[:, 1], position[:, 0]) + rng.choice([-1, 1]) * 0.6
    angles[:, 0] += outward
    angles[:, 1] += 0.35  # looking down a little, as at a desk or the floor ahead
    optical_in_body = Rotation.from_matrix([[0, 0, 1], [-1, 0, 0], [0, -1, 0]])
    poses = []
    for k in range(frames):
        body = Rotation.from_euler("ZYX", angles[k])
        pose = np.eye(4)
        pose[:3, :3] = (body * optical_in_body).as_matrix()
        pose[:3, 3] = position[k]
        poses.append(pose)
    return poses


def kinect_depth(depth_m: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The exact depth as a Kinect would report it (see the module docstring)."""
    z = depth_m.astype(np.float64)
    valid = (z > 0.4) & (z < MAX_RANGE_M) & (rng.random(z.shape) > 0.01)
    sigma = KINECT.base_m + KINECT.quadratic_per_m * (z - KINECT.offset_m) ** 2
    noisy = z + sigma * rng.standard_normal(z.shape)
    fb = KINECT_BASELINE_M * KINECT_FOCAL_PX
    disparity = np.round(fb / np.maximum(noisy, 0.1) / DISPARITY_STEP_PX) * DISPARITY_STEP_PX
    out = np.where(valid, fb / np.maximum(disparity, 1e-6), 0.0)
    return out


def write_sequence(out: Path, seed: int, frames: int, clutter: int = 40) -> None:
    """Render a sequence into ``out`` in the TUM layout."""
    rng = np.random.default_rng(seed)
    model = mujoco.MjModel.from_xml_string(room_xml(rng, clutter))
    data = mujoco.MjData(model)
    renderer = mujoco.Renderer(model, height=HEIGHT, width=WIDTH)
    renderer.enable_depth_rendering()
    (out / "depth").mkdir(parents=True, exist_ok=True)
    # MuJoCo cameras look along -z with y up; the optical frame along +z with y down.
    mujoco_in_optical = np.diag([1.0, -1.0, -1.0])
    depth_lines, truth_lines = [], []
    for k, pose in enumerate(hand_held_path(rng, frames)):
        stamp = 1.0 + k / RATE_HZ
        data.mocap_pos[0] = pose[:3, 3]
        quat = Rotation.from_matrix(pose[:3, :3] @ mujoco_in_optical).as_quat()
        data.mocap_quat[0] = [quat[3], *quat[:3]]
        mujoco.mj_forward(model, data)
        renderer.update_scene(data, camera="depth")
        depth = kinect_depth(renderer.render(), rng)
        name = f"depth/{stamp:.6f}.png"
        units = np.clip(np.round(depth / TUM_DEPTH_SCALE), 0, 65535).astype(np.uint16)
        Image.fromarray(units).save(out / name)
        depth_lines.append(f"{stamp:.6f} {name}")
        q = Rotation.from_matrix(pose[:3, :3]).as_quat()
        truth_lines.append(f"{stamp:.6f} " + " ".join(f"{v:.7f}" for v in (*pose[:3, 3], *q)))
    renderer.close()
    (out / "depth.txt").write_text("\n".join(depth_lines) + "\n")
    (out / "groundtruth.txt").write_text("\n".join(truth_lines) + "\n")


def main() -> None:
    """Render one sequence."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--frames", type=int, default=900)
    args = parser.parse_args()
    write_sequence(args.out, args.seed, args.frames)
    print(f"Wrote {args.frames} frames to {args.out}; intrinsics {' '.join(map(str, INTRINSICS))}")


if __name__ == "__main__":
    main()
