"""Writes the test arm whose links are meshes: ``mesharm/meshes/capsule.stl`` (a capsule,
ASCII STL), ``mesharm/meshes/ell.obj`` (an L of two boxes, OBJ) and
``mesharm/urdf/mesh_arm.urdf`` naming them by ``package://mesharm/...`` URIs.

Run ``python tests/streams/motion/meshes/make_meshes.py`` to rewrite them next to this script;
``test_sphere_fit.py`` checks that the files here are what it writes.
"""

from __future__ import annotations

import itertools
import sys
from pathlib import Path

import numpy as np

URDF = """<?xml version="1.0"?>
<robot name="mesh_arm">
  <link name="base_link">
    <collision><geometry><box size="0.2 0.2 0.1"/></geometry></collision>
  </link>
  <joint name="joint1" type="revolute">
    <parent link="base_link"/><child link="link1"/>
    <origin xyz="0 0 0.05"/><axis xyz="0 0 1"/>
    <limit lower="-3.14" upper="3.14" effort="1" velocity="1"/>
  </joint>
  <link name="link1">
    <collision>
      <origin xyz="0 0 0.2"/>
      <geometry><mesh filename="package://mesharm/meshes/capsule.stl"/></geometry>
    </collision>
  </link>
  <joint name="joint2" type="revolute">
    <parent link="link1"/><child link="link2"/>
    <origin xyz="0 0 0.4"/><axis xyz="0 1 0"/>
    <limit lower="-3.14" upper="3.14" effort="1" velocity="1"/>
  </joint>
  <link name="link2">
    <collision>
      <geometry><mesh filename="package://mesharm/meshes/ell.obj"/></geometry>
    </collision>
  </link>
  <joint name="hand_joint" type="fixed">
    <parent link="link2"/><child link="hand"/>
    <origin xyz="0.2 0 0" rpy="0 1.5707963267948966 0"/>
  </joint>
  <link name="hand">
    <collision>
      <geometry>
        <mesh filename="package://mesharm/meshes/capsule.stl" scale="0.5 0.5 0.3"/>
      </geometry>
    </collision>
  </link>
</robot>
"""


def capsule(radius: float = 0.04, half_length: float = 0.15, sides: int = 16) -> str:
    """An ASCII STL of a closed capsule on the z axis centred at the origin."""
    cap = np.linspace(0.0, np.pi / 2, 5)
    profile = [(radius * np.sin(t), -half_length - radius * np.cos(t)) for t in cap]
    profile += [(radius * np.sin(t), half_length + radius * np.cos(t)) for t in cap[::-1]]
    a = 2.0 * np.pi * np.arange(sides) / sides
    rings = [
        np.stack([r * np.cos(a), r * np.sin(a), np.full(sides, z)], axis=1) for r, z in profile
    ]
    facets = []
    for lower, upper in itertools.pairwise(rings):
        for j in range(sides):
            k = (j + 1) % sides
            for tri in ((lower[j], lower[k], upper[k]), (lower[j], upper[k], upper[j])):
                if np.linalg.norm(np.cross(tri[1] - tri[0], tri[2] - tri[0])) > 1e-12:
                    facets.append(tri)
    lines = ["solid capsule"]
    for tri in facets:
        n = np.cross(tri[1] - tri[0], tri[2] - tri[0])
        n = n / np.linalg.norm(n)
        lines += [f"  facet normal {n[0]:.9f} {n[1]:.9f} {n[2]:.9f}", "    outer loop"]
        lines += [f"      vertex {p[0]:.9f} {p[1]:.9f} {p[2]:.9f}" for p in tri]
        lines += ["    endloop", "  endfacet"]
    return "\n".join([*lines, "endsolid capsule", ""])


def ell() -> str:
    """An OBJ of an L: two boxes (0.25 x 0.05 x 0.05 along x, 0.05 x 0.15 x 0.05 along y)."""
    lines = ["# an L of two boxes"]
    faces = ((1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4))
    for n, (lo, hi) in enumerate((((0, -0.025, -0.025), (0.25, 0.025, 0.025)),
                                   ((0, -0.025, -0.025), (0.05, 0.15, 0.025)))):  # fmt: skip
        for i in range(8):
            x, y, z = (hi[d] if (i >> (2 - d)) & 1 else lo[d] for d in range(3))
            lines.append(f"v {x:.6f} {y:.6f} {z:.6f}")
        for f in faces:
            a, b, c, d = (8 * n + i for i in f)
            lines += [f"f {a} {b} {c}", f"f {a} {c} {d}"]
    return "\n".join([*lines, ""])


def write(root: Path) -> Path:
    """Writes the package ``mesharm`` under ``root``; returns the URDF's path."""
    (root / "mesharm" / "meshes").mkdir(parents=True, exist_ok=True)
    (root / "mesharm" / "urdf").mkdir(parents=True, exist_ok=True)
    (root / "mesharm" / "meshes" / "capsule.stl").write_text(capsule(), encoding="utf-8")
    (root / "mesharm" / "meshes" / "ell.obj").write_text(ell(), encoding="utf-8")
    urdf = root / "mesharm" / "urdf" / "mesh_arm.urdf"
    urdf.write_text(URDF, encoding="utf-8")
    return urdf


if __name__ == "__main__":
    print(write(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parent))
