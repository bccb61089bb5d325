"""``orchestra plot``: field specs as rqt_plot reads them, and the picture itself: the curve
is found in the PNG's pixels where the data puts it (and not where it does not)."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from orchestra.bag.writer import BagWriter
from orchestra.node.msg import get_message_class
from orchestra.plot.series import SpecError, parse_path, parse_spec

sys.path.insert(0, str(Path(__file__).resolve().parent / "node_fixtures"))
from harness import NodeProcess  # noqa: E402

HERE = Path(__file__).resolve().parent

T0 = 1_700_000_000 * 10**9
C0 = (0x1F / 255, 0x77 / 255, 0xB4 / 255)  # matplotlib's first line colour


def test_spec_names_fields_of_the_longest_topic_prefix():
    topics = ["/turtle1/pose", "/turtle1", "/scan"]
    got = parse_spec("/turtle1/pose/x:y", topics)
    assert [(s.topic, s.path, s.label) for s in got] == [
        ("/turtle1/pose", ["x"], "/turtle1/pose/x"), ("/turtle1/pose", ["y"], "/turtle1/pose/y")]
    assert parse_path("ranges[3]") == ["ranges", 3]
    assert parse_spec("/scan/ranges[3]", topics)[0].label == "/scan/ranges[3]"
    with pytest.raises(SpecError, match="no such topic"):
        parse_spec("/nope/x", topics)
    with pytest.raises(SpecError, match="name a numeric field"):
        parse_spec("/scan", topics)


def _triangle(t: float) -> float:
    return t if t <= 5 else 10 - t


def _bag(path) -> None:
    cls = get_message_class("std_msgs/Float64")
    w = BagWriter(str(path)).open()
    conn = w.add_connection("/value", {"type": cls._type, "md5sum": cls._md5sum,
                                       "message_definition": cls._full_text,
                                       "callerid": "/gen", "latching": "0"})
    for i in range(201):
        t = i * 0.05
        w.write(conn, T0 + int(t * 1e9), bytes(cls(data=_triangle(t)).serialize_bytes()))
    w.close()


def _near_curve(img, row: float, col: float, radius: int = 3) -> bool:
    import numpy as np
    r, c = int(round(row)), int(round(col))
    assert radius <= r < img.shape[0] - radius and radius <= c < img.shape[1] - radius
    patch = img[max(0, r - radius):r + radius + 1, max(0, c - radius):c + radius + 1, :3]
    return bool((np.abs(patch - np.array(C0)).sum(axis=2) < 0.25).any())


def test_plot_png_draws_the_curve_where_the_data_is(tmp_path):
    import matplotlib.image

    from orchestra.plot import figure
    from orchestra.plot.cli import series_from_bag
    bag = tmp_path / "tri.bag"
    _bag(bag)
    series = series_from_bag(str(bag), ("/value/data",))
    out = tmp_path / "tri.png"
    fig = figure.save(series, str(out))
    img = matplotlib.image.imread(str(out))
    height = img.shape[0]
    ax = fig.axes[0]
    for t in (1.0, 2.5, 4.0, 6.0, 8.5):
        x, y = ax.transData.transform((t, _triangle(t)))
        assert _near_curve(img, height - y, x), f"no curve at t={t}"
        away = _triangle(t) + (2.5 if _triangle(t) < 2.5 else -2.5)
        x, y = ax.transData.transform((t, away))
        assert not _near_curve(img, height - y, x), f"curve where the data is not, t={t}"


def test_plot_cli_writes_a_picture_from_a_bag_and_rejects_bad_specs(tmp_path):
    bag = tmp_path / "tri.bag"
    _bag(bag)
    run = [sys.executable, "-m", "orchestra", "plot", "--bag", str(bag)]
    env = dict(os.environ)
    env.pop("DISPLAY", None)
    ok = subprocess.run(run + ["/value/data", "--out", str(tmp_path / "p.svg")],
                        capture_output=True, text=True, env=env)
    assert ok.returncode == 0, ok.stderr
    assert (tmp_path / "p.svg").read_text().lstrip().startswith("<?xml")
    for spec, problem in (("/value/nope", "has no field"), ("/other/x", "no such topic")):
        bad = subprocess.run(run + [spec, "--out", str(tmp_path / "q.png")],
                             capture_output=True, text=True, env=env)
        assert bad.returncode == 2 and problem in bad.stderr, bad.stderr
        assert len(bad.stderr.strip().splitlines()) == 1
    nodisplay = subprocess.run(run + ["/value/data"], capture_output=True, text=True, env=env)
    assert nodisplay.returncode == 2 and "--out" in nodisplay.stderr


def test_plot_live_topic_to_a_picture(master, tmp_path):
    env = dict(os.environ, ROS_MASTER_URI=master.uri, PYTHONUNBUFFERED="1")
    env.pop("DISPLAY", None)
    env.pop("ROS_NAMESPACE", None)
    pub = NodeProcess([sys.executable, str(HERE / "node_fixtures" / "pub.py"), "/value",
                       "std_msgs/Float64", "data: $N", "--rate", "50"], env)
    try:
        pub.ready(timeout=20)
        out = tmp_path / "live.png"
        proc = subprocess.run([sys.executable, "-m", "orchestra", "plot", "/value/data",
                               "--out", str(out), "--duration", "1.5"], capture_output=True,
                              text=True, env=env, timeout=60)
        assert proc.returncode == 0 and "no data" not in proc.stderr, proc.stderr
        assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    finally:
        pub.kill()
        pub.close_pipes()


def test_plot_live_waits_for_a_topic_that_does_not_exist_yet(master, tmp_path):
    """rqt_plot waits for the topic; ``orchestra plot`` said "no such topic" at once."""
    env = dict(os.environ, ROS_MASTER_URI=master.uri, PYTHONUNBUFFERED="1")
    env.pop("DISPLAY", None)
    env.pop("ROS_NAMESPACE", None)
    out = tmp_path / "late.png"
    plot = subprocess.Popen([sys.executable, "-m", "orchestra", "plot", "/late/linear/x",
                             "--out", str(out), "--duration", "1.5"], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    pub = None
    try:
        assert "waiting for topic /late/linear/x" in plot.stderr.readline()
        pub = NodeProcess([sys.executable, str(HERE / "node_fixtures" / "pub.py"), "/late",
                           "geometry_msgs/Twist", "linear: {x: $N}", "--rate", "50"], env)
        pub.ready(timeout=20)
        _, err = plot.communicate(timeout=60)
        assert plot.returncode == 0 and "no data" not in err, err
        assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    finally:
        if plot.poll() is None:
            plot.kill()
            plot.communicate()
        if pub is not None:
            pub.kill()
            pub.close_pipes()
