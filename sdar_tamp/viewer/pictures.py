"""Picture files: draw an instance, or a plan on it, to a file whose suffix picks the
picture (``sdar show`` calls :func:`show`)."""

from __future__ import annotations

from pathlib import Path

from sdar_tamp.arguments import FPS, optional
from sdar_tamp.errors import ParameterError

#: Output suffixes with a plan: 3-D replay, storyboard, top-down animation.
PLAN_SUFFIXES = (".html", ".png", ".gif")
#: Output suffixes without a plan: the 3-D start scene, or a top-down start/goal picture.
INSTANCE_SUFFIXES = (".html", ".png", ".pdf", ".svg", ".jpg", ".jpeg")


def check_output(out: Path, with_plan: bool) -> None:
    """Raise :class:`ParameterError` unless ``out``'s suffix is one :func:`show` can write."""
    suffix = Path(out).suffix.lower()
    if with_plan and suffix not in PLAN_SUFFIXES:
        raise ParameterError(
            f"output must end in one of {', '.join(PLAN_SUFFIXES)} when a plan is given, "
            f"got {Path(out).name!r}"
        )
    if not with_plan and suffix == ".gif":
        raise ParameterError(
            "output: a .gif animation needs a plan (sdar show INSTANCE PLAN.json -o OUT.gif); "
            "without a plan use .png or .html"
        )
    if not with_plan and suffix not in INSTANCE_SUFFIXES:
        raise ParameterError(
            f"output must end in one of {', '.join(INSTANCE_SUFFIXES)} without a plan "
            f"(with a plan also .gif), got {Path(out).name!r}"
        )


def show(instance_path: Path, plan_path: Path | None, out: Path, fps: float | None = None) -> Path:
    """Draw the instance file (and the plan file, if given) to ``out``; return what was written.

    With a plan: ``.html`` -> interactive 3-D replay, ``.png`` -> storyboard, ``.gif`` ->
    top-down animation. Without: ``.html`` -> the scene at the start in 3-D, ``.png``,
    ``.pdf``, ``.svg``, ``.jpg`` -> start and goal side by side with the dependency graph.
    ``fps`` [1/s]: animation frames per second of plan time, finite and > 0 (default: 10 for
    HTML, 4 for GIF). Missing parent folders of ``out`` are created; ``out`` is replaced.
    """
    from sdar_tamp.world.instance import load_instance
    from sdar_tamp.world.scene import load_scene

    instance_path, out = Path(instance_path), Path(out)
    check_output(out, plan_path is not None)
    fps = optional(FPS, "fps", fps)
    suffix = out.suffix.lower()
    instance = load_instance(instance_path)
    out.parent.mkdir(parents=True, exist_ok=True)
    if plan_path is None and suffix != ".html":
        from sdar_tamp.world.draw import draw_instance

        return draw_instance(instance, out)
    scene = load_scene(instance.scene_path(instance_path))
    from sdar_tamp.viewer.html import write_html
    from sdar_tamp.viewer.storyboard import write_storyboard

    if plan_path is None:
        return write_html(instance, None, out, scene)
    from sdar_tamp.plan_reading import load_plan

    plan = load_plan(Path(plan_path))
    if suffix == ".html":
        return write_html(instance, plan, out, scene, fps=fps or 10.0)
    return write_storyboard(instance, plan, out, scene, fps=max(1, round(fps or 4)))
