"""meshcat scenes, static HTML and PNG snapshots (one Chromium launch for all), the UR10 cell."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from hexapod_model.analysis.trajectories import box_poses
from hexapod_model.cli.main import main
from hexapod_model.cli.view import play_frames
from hexapod_model.viz import render, robot_cell
from hexapod_model.viz.meshcat_scene import (
    HexapodScene,
    ViewError,
    solve_view_configuration,
    start_visualizer,
    stop_visualizer,
)
from hexapod_model.viz.render import pixels
from hexapod_model.viz.robot_cell import add_cell

from ..conftest import HAVE_CELL, PRESET_NAMES, hexapod

MOVED = (0.03, -0.02, 0.0, 12.0, -8.0, 20.0)  # x, y, dz (m) and roll, pitch, yaw (deg) from home


def moved_pose(hexa):
    x, y, dz, r, p, yw = MOVED
    return (x, y, hexa.home_pose[2, 3] + dz, r, p, yw)


@pytest.fixture(scope="module")
def snapshots(tmp_path_factory):
    """HTML of every preset at home, the reference moved, and the reference in its cell,
    rendered to PNG in a single Chromium launch."""
    out = tmp_path_factory.mktemp("snapshots")
    vis = start_visualizer()
    cases = {name: (name, False, False) for name in PRESET_NAMES}
    cases["reference-moved"] = ("reference", True, False)
    if HAVE_CELL:  # the UR10 (example-robot-data); without it, the cell's own tests are skipped with the hint
        cases["reference-cell"] = ("reference", True, True)
    html = {}
    try:
        for name, (preset, moved, cell) in cases.items():
            vis.delete()
            hexa = hexapod(preset)
            scene = HexapodScene(hexa, vis)
            sol = solve_view_configuration(hexa, pose_xyz_rpy=moved_pose(hexa) if moved else None)
            scene.show(sol)
            if cell:
                add_cell(scene, sol)
            html[name] = render.write_html(vis, out / f"{name}.html")
    finally:
        stop_visualizer(vis)
    names = list(cases)
    pngs = render.render_pngs([html[n] for n in names], [out / f"{n}.png" for n in names])
    return html, dict(zip(names, pngs))


@pytest.mark.chromium
def test_html_is_a_self_contained_meshcat_scene(snapshots):
    html, _ = snapshots
    for name, path in html.items():
        text = path.read_text()
        assert "<title>MeshCat</title>" in text and "handle_command_bytearray" in text, name
        assert "127.0.0.1" not in text  # no server needed to open it
    if HAVE_CELL:
        assert html["reference-cell"].stat().st_size > 3 * html["reference"].stat().st_size  # UR10 meshes inside


@pytest.mark.chromium
@pytest.mark.parametrize("name", [*PRESET_NAMES, pytest.param("reference-cell", marks=pytest.mark.cell)])
def test_png_shows_something(snapshots, name):
    img = pixels(snapshots[1][name])
    assert img.shape[:2] == (960, 1280)
    drawn = np.any(img < 235, axis=2).mean()  # non-white pixels
    assert 0.03 < drawn < 0.8, f"{name}: {drawn:.3f} of the picture is drawn"
    assert img.std() > 20
    # colours of the mechanism: orange leg cylinders (cardan/spherical) or blue plate (all)
    blue = (img[..., 2] > 150) & (img[..., 0] < 100)
    assert blue.mean() > 0.002  # the top plate (a few thousand pixels even in the wide cell view)


@pytest.mark.chromium
def test_png_changes_with_the_pose(snapshots):
    home = pixels(snapshots[1]["reference"]).astype(float)
    moved = pixels(snapshots[1]["reference-moved"]).astype(float)
    changed = np.any(np.abs(home - moved) > 30, axis=2).mean()
    assert changed > 0.01


def test_missing_chromium_names_the_package(monkeypatch, tmp_path):
    monkeypatch.setattr(shutil, "which", lambda name: None)
    with pytest.raises(render.RenderError, match="Debian package `chromium`"):
        render.render_pngs([tmp_path / "a.html"], [tmp_path / "a.png"])


def test_snapshot_png_without_chromium_fails_before_writing_the_html(monkeypatch, tmp_path, capsys):
    monkeypatch.setattr(shutil, "which", lambda name: None)
    html, png = tmp_path / "s.html", tmp_path / "s.png"
    assert main(["snapshot", "reference", "-o", str(html), "--png", str(png)]) == 2
    assert "Debian package `chromium`" in capsys.readouterr().err
    assert not html.exists() and not png.exists()


def test_small_png_size_is_refused(tmp_path):
    with pytest.raises(render.RenderError, match="below the minimum 1024x768"):
        render.render_pngs([tmp_path / "a.html"], [tmp_path / "a.png"], size=(640, 480))


@pytest.mark.cell
def test_cell_ik_reaches_the_tool_changer():
    hexa = hexapod("reference")
    sol = solve_view_configuration(hexa, pose_xyz_rpy=moved_pose(hexa))
    cell = robot_cell.couple_to_plate(sol.pose)
    target = robot_cell.tool_changer_pose(sol.pose)
    np.testing.assert_allclose(cell.flange, target, atol=1e-6)
    assert cell.flange[2, 2] < -0.9  # flange z points down onto the plate


@pytest.mark.cell
def test_unreachable_plate_pose_is_an_error():
    T = hexapod("reference").home_pose.copy()
    T[0, 3] = -1.5  # far side of the hexapod, out of the UR10's reach
    with pytest.raises(robot_cell.UnreachableError, match="cannot reach the tool-changer pose"):
        robot_cell.couple_to_plate(T)
    T = hexapod("reference").home_pose.copy()
    T[:3, :3] = np.diag([1.0, -1.0, -1.0])  # plate upside down: flange would have to point up from below
    T[2, 3] = 0.05
    with pytest.raises(robot_cell.UnreachableError):
        robot_cell.couple_to_plate(T)


def test_view_configuration_inputs():
    hexa = hexapod("reference")
    assert solve_view_configuration(hexa).iterations == 0
    sol = solve_view_configuration(hexa, pose_xyz_rpy=moved_pose(hexa))
    np.testing.assert_allclose(sol.pose[:3, 3], moved_pose(hexa)[:3], atol=1e-12)
    back = solve_view_configuration(hexa, lengths=sol.lengths)
    np.testing.assert_allclose(back.pose, sol.pose, atol=1e-9)
    with pytest.raises(ViewError, match="either"):
        solve_view_configuration(hexa, lengths=sol.lengths, pose_xyz_rpy=moved_pose(hexa))


def test_play_csv_of_lengths_or_poses(tmp_path, capsys):
    hexa = hexapod("reference")
    sols = [hexa.inverse(T) for T in box_poses(hexa.home_pose, 4, seed=9)]
    (tmp_path / "l.csv").write_text(
        "l1,l2,l3,l4,l5,l6\n" + "\n".join(",".join(map(str, s.lengths)) for s in sols) + "\n0,nan,0,0,0,0\n"
    )
    frames = play_frames(hexa, tmp_path / "l.csv")
    assert len(frames) == 4 and "row 5 skipped" in capsys.readouterr().err
    np.testing.assert_allclose(frames[2].pose, sols[2].pose, atol=1e-9)
    assert main(["fk", "reference", str(tmp_path / "l.csv"), "-o", str(tmp_path / "p.csv")]) == 1
    frames = play_frames(hexa, tmp_path / "p.csv")  # fk's output, its failed row skipped
    assert len(frames) == 4
    np.testing.assert_allclose(frames[3].lengths, sols[3].lengths, atol=1e-9)


def test_cli_snapshot_and_view(tmp_path, capsys):
    assert main(["snapshot", "3-6", "--pose", "0.01", "0", "0.23", "5", "0", "0", "-o", str(tmp_path / "s.html")]) == 0
    assert (tmp_path / "s.html").read_text().count("handle_command_bytearray") >= 1
    assert (
        main(
            [
                "snapshot",
                "reference",
                "-o",
                str(tmp_path / "s.html"),
                "--png",
                str(tmp_path / "s.png"),
                "--size",
                "640x480",
            ]
        )
        == 2
    )
    assert "below the minimum" in capsys.readouterr().err
    assert (
        main(["snapshot", "reference", "--lengths", "0.5", "0", "0", "0", "0", "0", "-o", str(tmp_path / "x.html")])
        == 2
    )
    assert "stroke limit" in capsys.readouterr().err
    (tmp_path / "p.csv").write_text("x,y,z,roll,pitch,yaw\n0,0,0.40,0,0,0\n0.01,0,0.41,3,0,0\n")
    assert main(["view", "reference", "--play", str(tmp_path / "p.csv"), "--rate", "1000", "--once"]) == 0
    out = capsys.readouterr()
    assert "meshcat: http://127.0.0.1:" in out.out and "played 2 frames" in out.err
