import numpy as np
import pytest

from streams.grasps import pregrasp_offset, sample_grasps


def test_default_object_gives_the_six_grasp_set_top_down_first() -> None:
    grasps = sample_grasps((0.08, 0.04, 0.05), max_width=0.075)
    assert len(grasps) == 6  # 1 graspable side x 2 yaws (flips) x {0, +45, -45}
    assert [g.tilt for g in grasps[:2]] == [0.0, 0.0]
    assert grasps[2].tilt == pytest.approx(np.pi / 4) and grasps[4].tilt == pytest.approx(
        -np.pi / 4
    )
    for g in grasps:
        R = g.T_object_tcp[:3, :3]
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
        assert np.linalg.det(R) == pytest.approx(1.0)
        assert g.closing_axis == 1 and g.width == pytest.approx(0.04)
        np.testing.assert_allclose(abs(R[:, 1] @ np.array([0, 1.0, 0])), 1.0)  # closes along y
        # approach tilted by |tilt| from straight down, in the plane perpendicular to y
        assert np.arccos(-g.approach[2]) == pytest.approx(abs(g.tilt))
        assert g.approach[1] == pytest.approx(0.0)


def test_both_sides_graspable_short_side_first_and_more_angles() -> None:
    grasps = sample_grasps((0.05, 0.03, 0.05), 0.075, tilts=(np.pi / 6, np.pi / 3))
    assert len(grasps) == 2 * 2 * 5
    assert grasps[0].closing_axis == 1 and grasps[2].closing_axis == 0
    tilts = [abs(g.tilt) for g in grasps]
    assert tilts == sorted(tilts)


def test_too_wide_object_is_rejected() -> None:
    assert sample_grasps((0.09, 0.08, 0.05), 0.075) == ()
    with pytest.raises(ValueError):
        sample_grasps((0.05, 0.03, 0.05), 0.075, tilts=(2.0,))


def test_pregrasp_backs_off_along_the_approach() -> None:
    g = sample_grasps((0.08, 0.04, 0.05), 0.075)[2]
    pre = pregrasp_offset(g.T_object_tcp, 0.08)
    np.testing.assert_allclose(pre[:3, 3] - g.T_object_tcp[:3, 3], -0.08 * g.approach)
