"""UR DH parameters read from the URDF: the shipped UR5e gives back its constants exactly."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sdar_tamp.world._pin import PinRobot
from sdar_tamp.world.kinematics import T_BASE_DH
from sdar_tamp.world.scene import domain_path
from sdar_tamp.world.ur_identify import ur_parameters
from sdar_tamp.world.ur_ik import UR5E, URParameters, ur_fk, ur_ik

UR5E_URDF = domain_path("robots/ur5e_2f85.urdf")


def test_the_shipped_ur5e_reads_back_exactly() -> None:
    found = ur_parameters(PinRobot.load(UR5E_URDF))
    assert found is not None
    params, T_root_dh = found
    assert params == UR5E  # bit for bit: the closed-form IK is today's
    np.testing.assert_array_equal(T_root_dh, T_BASE_DH)
    rng = np.random.default_rng(3)
    targets = ur_fk(UR5E, rng.uniform(-np.pi, np.pi, (20, 6)))
    a, b = ur_ik(params, targets), ur_ik(UR5E, targets)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])


def _ur_variant(tmp_path: Path, scale: float) -> Path:
    """The shipped URDF with every joint origin length scaled (a larger UR of the family)."""
    import re

    text = UR5E_URDF.read_text(encoding="utf-8")

    def scaled(match: re.Match[str]) -> str:
        values = " ".join(repr(round(float(v) * scale, 6)) for v in match.group(2).split())
        return f'{match.group(1)}"{values}"'

    text = re.sub(r'(<origin xyz=)"([^"]*)"', scaled, text)
    path = tmp_path / "big.urdf"
    path.write_text(text, encoding="utf-8")
    return path


def test_a_scaled_ur_reads_back_its_lengths(tmp_path: Path) -> None:
    found = ur_parameters(PinRobot.load(_ur_variant(tmp_path, 1.5)))
    assert found is not None
    expected = [round(v * 1.5, 6) for v in (0.1625, -0.425, -0.3922, 0.1333, 0.0997, 0.0996)]
    np.testing.assert_allclose(list(vars(found[0]).values()), expected, atol=1e-9)


def test_other_arms_are_not_ur(tmp_path: Path) -> None:
    text = UR5E_URDF.read_text(encoding="utf-8")
    # a tilted elbow axis breaks the parallel-axes structure
    bent = text.replace(
        '<joint name="elbow_joint" type="revolute">',
        '<joint name="elbow_joint" type="revolute">\n    <axis xyz="0 0.2 0.98"/>',
        1,
    )
    path = tmp_path / "bent.urdf"
    path.write_text(bent, encoding="utf-8")
    assert ur_parameters(PinRobot.load(path)) is None
    # a chain of another length
    assert ur_parameters(PinRobot.load(UR5E_URDF), flange="wrist_2_link") is None
    assert isinstance(UR5E, URParameters)


def test_a_scene_whose_arm_is_not_ur_gets_the_numeric_ik(tmp_path: Path) -> None:
    import numpy as np

    from sdar_tamp.world.kinematics import NUMERIC_BRANCHES, ArmKinematics
    from sdar_tamp.world.scene import default_scene_path, load_scene

    text = UR5E_URDF.read_text(encoding="utf-8").replace(
        '<joint name="elbow_joint" type="revolute">',
        '<joint name="elbow_joint" type="revolute">\n    <axis xyz="0 0.2 0.98"/>',
        1,
    )
    (tmp_path / "bent.urdf").write_text(text, encoding="utf-8")
    scene = (
        default_scene_path()
        .read_text(encoding="utf-8")
        .replace("robot: ../robots/ur5e_2f85.urdf", "robot: bent.urdf")
    )
    (tmp_path / "scene.yaml").write_text(scene, encoding="utf-8")
    bent = ArmKinematics.from_scene(load_scene(tmp_path / "scene.yaml"), "left")
    assert not bent.closed_form and bent.params is None and bent.branches == NUMERIC_BRANCHES
    home = np.array(bent.spec.home)
    target = bent.fk_tool0(home)
    sol = bent.ik_tool0(target)
    assert sol.q.shape == (1, NUMERIC_BRANCHES, 6) and sol.valid[0, 0]
    np.testing.assert_allclose(bent.fk_tool0(sol.q[0, 0]), target, atol=1e-5)
    found = ArmKinematics.from_scene(load_scene(), "left")
    assert found.params == UR5E and found.closed_form
