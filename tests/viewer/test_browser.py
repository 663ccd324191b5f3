"""The HTML viewer page in a real browser (headless Chromium), driven as a user would."""

from __future__ import annotations

import os
import re
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from sdar_tamp.plan_file import PlanFile
from sdar_tamp.viewer import write_html
from sdar_tamp.world.instance import Instance
from tests.viewer.conftest import CHROMIUM, broken, page_json


# -- a real browser -------------------------------------------------------------------------------
def _chromium(url: str, workdir: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    profile = tempfile.mkdtemp(prefix="chromium-", dir=workdir)
    cmd = [
        str(CHROMIUM), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
        "--no-first-run", "--disable-background-networking", "--disable-component-update",
        "--disable-sync", f"--user-data-dir={profile}", "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader", "--enable-logging=stderr", "--v=0",
        "--window-size=1200,900", "--virtual-time-budget=20000", "--hide-scrollbars",
        *extra, url,
    ]  # fmt: skip
    env = {**os.environ, "HOME": str(workdir)}
    return subprocess.run(cmd, capture_output=True, text=True, timeout=600, env=env, check=False)


needs_chromium = pytest.mark.skipif(
    not CHROMIUM.exists(), reason="chromium is not installed (apt-get install chromium)"
)


def _js_errors(stderr: str) -> list[str]:
    return [
        line
        for line in stderr.splitlines()
        if "Uncaught" in line or ("CONSOLE" in line and "Error" in line)
    ]


def _body(dom: str) -> dict[str, str]:
    """The attributes of the page's ``<body>`` after the run (the viewer's published state)."""
    m = re.search(r"<body([^>]*)>", dom)
    assert m is not None
    return dict(re.findall(r'([\w-]+)="([^"]*)"', m.group(1)))


def _with_script(page: Path, script: str) -> Path:
    """A copy of ``page`` running ``script`` once the viewer is ready (a user at the controls)."""
    html = page.read_text(encoding="utf-8")
    hook = "<script>window.addEventListener('sdar-ready', function () {" + script + "});</script>"
    out = page.with_name(page.stem + ".driven.html")
    out.write_text(html.replace("</body>", hook + "</body>"), encoding="utf-8")
    return out


@needs_chromium
def test_page_renders_in_headless_chromium(
    instance: Instance, plan: PlanFile, tmp_path: Path
) -> None:
    page = write_html(instance, plan, tmp_path / "replay.html", fps=5)
    t_mid = plan.duration / 2  # both arms carrying
    url = page.resolve().as_uri() + f"#t={t_mid:.2f}"
    started = time.monotonic()
    shot = tmp_path / "shot.png"
    run = _chromium(url, tmp_path, f"--screenshot={shot}", "--dump-dom")
    assert shot.is_file(), run.stderr[-2000:]
    assert not _js_errors(run.stderr), _js_errors(run.stderr)
    body = _body(run.stdout)
    assert body.get("data-sdar-ready") == str(len(page_json(page.read_text())["times"]))
    assert float(body["data-sdar-t"]) == pytest.approx(t_mid, abs=0.006)  # opened at #t=
    text = _visible_text(run.stdout)
    assert "WebGL" not in text and "could not" not in text
    assert re.search(r"left : gripper closed , holding o0", text), text[-600:]
    assert re.search(r"right : gripper closed , holding o1", text), text[-600:]
    assert "valid (sdar validate)" in text and 'id="sdar-banner" hidden' in run.stdout
    with Image.open(shot) as image:
        assert image.size == (1200, 900)
        view = np.asarray(image.convert("RGB"))[60:760, :740]  # the 3-D view
        panel = np.asarray(image.convert("RGB"))[60:760, 780:]  # the joint panel
    pixels = view.reshape(-1, 3)
    not_white = np.any(pixels < 235, axis=1).mean()
    distinct = len(np.unique(pixels // 8, axis=0))
    arms = [_near(pixels, (0x5B, 0x8F, 0xD1)), _near(pixels, (0xE0, 0x8A, 0x4F))]  # both arms
    assert not_white > 0.10 and distinct > 200 and min(arms) > 3000, (not_white, distinct, arms)
    curves = np.any(panel.reshape(-1, 3) < 200, axis=1).mean()
    assert curves > 0.01, curves  # the joint curves are drawn
    print(
        f"chromium: {time.monotonic() - started:.1f} s, {not_white:.0%} drawn, {distinct} colours"
    )


@needs_chromium
def test_step_buttons_and_speed_drive_the_time(
    instance: Instance, plan: PlanFile, tmp_path: Path
) -> None:
    page = write_html(instance, plan, tmp_path / "replay.html", fps=5)
    script = """
      var log = [], b = document.body;
      function note() {
        log.push(b.getAttribute('data-sdar-t') + '@' + b.getAttribute('data-sdar-step'));
      }
      note();
      document.getElementById('sdar-next').click(); note();
      document.getElementById('sdar-next').click(); note();
      document.getElementById('sdar-prev').click(); note();
      document.querySelectorAll('.sdar-step')[3].click(); note();
      var speed = document.getElementById('sdar-speed');
      speed.value = '4'; speed.dispatchEvent(new Event('change'));
      b.setAttribute('data-test-steps', String(document.querySelectorAll('.sdar-step').length));
      b.setAttribute('data-test-events', String(document.querySelectorAll('.sdar-ev').length));
      b.setAttribute('data-test-log', log.join(' '));
    """
    run = _chromium(_with_script(page, script).resolve().as_uri(), tmp_path, "--dump-dom")
    assert not _js_errors(run.stderr), _js_errors(run.stderr)
    body = _body(run.stdout)
    starts = [s.t_start for s in plan.steps]
    expected = [(0.0, 0), (starts[1], 1), (starts[2], 2), (starts[1], 1), (starts[3], 3)]
    log = [(float(t), int(k)) for t, k in (e.split("@") for e in body["data-test-log"].split())]
    assert [k for _, k in log] == [k for _, k in expected]
    np.testing.assert_allclose([t for t, _ in log], [t for t, _ in expected], atol=0.001)
    assert body["data-sdar-speed"] == "4"
    assert body["data-test-steps"] == str(len(plan.steps))
    assert body["data-test-events"] == str(len(plan.events))


@needs_chromium
def test_banner_shows_the_first_violation(
    instance: Instance, plan: PlanFile, tmp_path: Path
) -> None:
    bad, _ = broken(plan)
    page = write_html(instance, bad, tmp_path / "bad.html", fps=5)
    violation = page_json(page.read_text(encoding="utf-8"))["violation"]
    script = "document.getElementById('sdar-goto').click();"
    shot = tmp_path / "bad.png"
    run = _chromium(
        _with_script(page, script).resolve().as_uri(),
        tmp_path,
        f"--screenshot={shot}",
        "--dump-dom",
    )
    assert not _js_errors(run.stderr), _js_errors(run.stderr)
    banner = re.search(r'<div id="sdar-banner"([^>]*)>(.*?)</div>', run.stdout, re.S)
    assert banner is not None and "hidden" not in banner.group(1)
    assert f'data-kind="{violation["kind"]}"' in banner.group(1)
    assert f"invalid at t = {violation['t']:.2f} s" in banner.group(2)
    assert 'id="sdar-violation-mark"' in run.stdout  # on the time line
    assert float(_body(run.stdout)["data-sdar-t"]) == pytest.approx(violation["t"], abs=0.001)
    with Image.open(shot) as image:  # the banner is drawn: a red strip at the top
        top = np.asarray(image.convert("RGB"))[2:20, 200:1000].reshape(-1, 3).astype(int)
    red = (top[:, 0] > 150) & (top[:, 1] < 90) & (top[:, 2] < 90)
    assert red.mean() > 0.5, red.mean()


@needs_chromium
def test_a_browser_that_cannot_unpack_the_page_is_told(
    instance: Instance, plan: PlanFile, tmp_path: Path
) -> None:
    page = write_html(instance, plan, tmp_path / "replay.html", fps=5)
    old = page.with_name("old.html")
    html = page.read_text(encoding="utf-8")
    old.write_text(html.replace("<body>", "<body><script>window.DecompressionStream = undefined;"
                                "</script>", 1), encoding="utf-8")  # fmt: skip
    run = _chromium(old.resolve().as_uri(), tmp_path, "--dump-dom")
    banner = re.search(r'<div id="sdar-banner"([^>]*)>(.*?)</div>', run.stdout, re.S)
    assert banner is not None and "hidden" not in banner.group(1)
    assert "cannot unpack the page" in banner.group(2)
    assert "data-sdar-ready" not in _body(run.stdout)  # never drawn


def _near(pixels: np.ndarray, rgb: tuple[int, int, int], tol: int = 60) -> int:
    """Pixels within ``tol`` of the hue family of ``rgb`` (shading changes the brightness)."""
    p = pixels.astype(float)
    ref = np.array(rgb, dtype=float)
    cos = (p @ ref) / (np.linalg.norm(p, axis=1) * np.linalg.norm(ref) + 1e-9)
    spread = p.max(axis=1) - p.min(axis=1)
    return int(((cos > 0.985) & (spread > tol)).sum())


def _visible_text(dom: str) -> str:
    body = re.sub(r"<(script|style).*?</\1>", "", dom, flags=re.S)
    return re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", body))
