"""The function behind ``sdar show``: draw an instance, or a plan on it, to a file."""

from __future__ import annotations

from pathlib import Path

from sdar_tamp.errors import ParameterError

#: Output suffixes with a plan; without one, ``.html`` draws the start scene in 3-D, ``.gif`` is
#: an error and anything else is the top-down start/goal picture of the instance.
PLAN_SUFFIXES = (".html", ".png", ".gif")


def show(instance_path: Path, plan_path: Path | None, out: Path, fps: float | None = None) -> Path:
    """Draw the instance file (and the plan file, if given) to ``out``; return what was written.

    With a plan: ``.html`` -> interactive 3-D replay, ``.png`` -> storyboard, ``.gif`` ->
    top-down animation. Without: ``.html`` -> the scene at the start in 3-D, ``.gif`` -> error,
    other suffixes -> start and goal side by side with the dependency graph. ``fps`` [1/s]:
    animation frames per second of plan time (default: 10 for HTML, 4 for GIF).
    """
    from sdar_tamp.world.instance import load_instance
    from sdar_tamp.world.scene import load_scene

    instance_path, out = Path(instance_path), Path(out)
    suffix = out.suffix.lower()
    if plan_path is not None and suffix not in PLAN_SUFFIXES:
        raise ParameterError(
            f"output must end in one of {', '.join(PLAN_SUFFIXES)} when a plan is given, "
            f"got {out.name!r}"
        )
    if plan_path is None and suffix == ".gif":
        raise ParameterError(
            "output: a .gif animation needs a plan (sdar show INSTANCE PLAN.json -o OUT.gif); "
            "without a plan use .png or .html"
        )
    instance = load_instance(instance_path)
    if plan_path is None and suffix != ".html":
        from sdar_tamp.world.draw import draw_instance

        return draw_instance(instance, out)
    scene = load_scene(instance.scene_path(instance_path))
    from sdar_tamp.viewer.html import write_html
    from sdar_tamp.viewer.storyboard import write_storyboard

    if plan_path is None:
        return write_html(instance, None, out, scene)
    from sdar_tamp.plan_file import load_plan

    plan = load_plan(Path(plan_path))
    if suffix == ".html":
        return write_html(instance, plan, out, scene, fps=fps or 10.0)
    return write_storyboard(instance, plan, out, scene, fps=max(1, round(fps or 4)))
