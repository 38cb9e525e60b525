import csv

import numpy as np

from cli_inprocess import seatrack
from seatrack.simulate import Leg
from seatrack.simulate import NoiseModel
from seatrack.simulate import observe
from seatrack.simulate import trajectory


def _seatrack(*args, cwd):
    return seatrack(*args, cwd=cwd)


def _write_plots(path):
    tr = trajectory(
        [5000, 8000, 1000],
        np.radians(100),
        150,
        [Leg.straight(60), Leg.turn(np.pi / 2, np.radians(3))],
        dt=2.0,
    )
    m = observe(
        tr,
        None,
        ["range", "azimuth", "elevation", "range_rate"],
        NoiseModel([20, np.radians(0.3), np.radians(0.3), 1.0]),
        np.random.default_rng(0),
    )
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["track", "time_s", "range_m", "azimuth_deg", "elevation_deg", "range_rate_mps"])
        for tid in ("a", "b"):
            for i in range(len(m.t)):
                w.writerow(
                    [
                        tid,
                        m.t[i],
                        m.z[i, 0],
                        np.degrees(m.z[i, 1]),
                        np.degrees(m.z[i, 2]),
                        m.z[i, 3],
                    ]
                )
    return 2 * len(m.t)


def test_track_ekf_writes_one_row_per_plot(tmp_path):
    n = _write_plots(tmp_path / "plots.csv")
    cfg = tmp_path / "cfg.toml"
    cfg.write_text("q = 5.0\nsigma_range_m = 20.0\nsigma_azimuth_deg = 0.3\n")
    r = _seatrack(
        "track",
        "plots.csv",
        "--method",
        "ekf",
        "--config",
        "cfg.toml",
        "--out",
        "track.csv",
        cwd=tmp_path,
    )
    assert r.returncode == 0, r.stderr
    rows = list(csv.DictReader(open(tmp_path / "track.csv")))
    assert len(rows) == n
    assert {"track", "time_s", "x_m", "std_z_m", "nis"} <= set(rows[0])
    assert {row["track"] for row in rows} == {"a", "b"}


def test_track_errors_are_one_line_without_traceback(tmp_path):
    (tmp_path / "bad.csv").write_text("time_s,range_m,azimuth_deg\n0,100,10\n1,nan,10\n")
    r = _seatrack("track", "bad.csv", "--out", "o.csv", cwd=tmp_path)
    assert r.returncode == 2
    assert "bad.csv, line 3" in r.stderr and "Traceback" not in r.stderr
    _write_plots(tmp_path / "plots.csv")
    r = _seatrack("track", "plots.csv", "--method", "nope", "--out", "o.csv", cwd=tmp_path)
    assert r.returncode == 2 and "unknown method 'nope'" in r.stderr and "Traceback" not in r.stderr
    (tmp_path / "c.toml").write_text("q = = 1\n")
    r = _seatrack("track", "plots.csv", "--config", "c.toml", "--out", "o.csv", cwd=tmp_path)
    assert r.returncode == 2 and "c.toml: not valid TOML" in r.stderr


def _ok_plots(path, extra_row=""):
    path.write_text(
        "track,time_s,range_m,azimuth_deg\n"
        + "".join(f"A,{2 * k},{5000 + 10 * k},{30 + 0.01 * k}\n" for k in range(20))
        + extra_row
    )


def test_absurd_values_are_refused_with_their_line(tmp_path):
    """Issue 13: a range of 1e308, a 1e15 s time gap, an empty track id."""
    body = "".join(f"A,{2 * k},{5000 + 10 * k},30\n" for k in range(5))
    cases = {
        "range_m = 1e+308 is implausible": "A,10,1e308,30\n",
        "time_s = 1e+15 is implausible": "A,1000000000000010,5060,30\n",
        "time gap of 3e+06 s": "A,3000008,5060,30\n",
        "empty track id": ",12,5060,30\n",
    }
    for msg, row in cases.items():
        (tmp_path / "p.csv").write_text("track,time_s,range_m,azimuth_deg\n" + body + row)
        r = _seatrack("track", "p.csv", "--out", "o.csv", cwd=tmp_path)
        assert r.returncode == 2, (msg, r.stderr)
        assert f"p.csv, line 7: {msg}" in r.stderr and "Traceback" not in r.stderr, r.stderr
        assert not (tmp_path / "o.csv").exists()


def test_config_errors_name_the_file_and_key(tmp_path):
    _ok_plots(tmp_path / "p.csv")
    for text, msg in [
        ("sigma_rnage_m = 3.0\n", "c.toml: unknown key 'sigma_rnage_m'; valid keys:"),
        ('q = "abc"\n', "c.toml: q: expected a number, got 'abc'"),
        ('[sensor]\nsigma_range_m = "abc"\n', "c.toml: sigma_range_m: expected a number"),
        ("[sensor]\nsigma_range_m = -1.0\n", "c.toml: sigma_range_m: must be > 0"),
    ]:
        (tmp_path / "c.toml").write_text(text)
        r = _seatrack("track", "p.csv", "--config", "c.toml", "--out", "o.csv", cwd=tmp_path)
        assert r.returncode == 2 and msg in r.stderr and "Traceback" not in r.stderr, r.stderr


def test_sensor_table_is_used(tmp_path):
    _ok_plots(tmp_path / "p.csv")
    outs = []
    for text in ("[sensor]\nsigma_range_m = 1.0\n", "[sensor]\nsigma_range_m = 100.0\n"):
        (tmp_path / "c.toml").write_text(text)
        r = _seatrack("track", "p.csv", "--config", "c.toml", "--out", "o.csv", cwd=tmp_path)
        assert r.returncode == 0, r.stderr
        outs.append([float(row["std_x_m"]) for row in csv.DictReader(open(tmp_path / "o.csv"))])
    assert outs[0][-1] < outs[1][-1]


def test_output_checked_before_work_and_written_atomically(tmp_path):
    _ok_plots(tmp_path / "p.csv")
    (tmp_path / "adir").mkdir()
    r = _seatrack("track", "p.csv", "--out", "adir", cwd=tmp_path)
    assert r.returncode == 2 and "is a directory" in r.stderr and "Traceback" not in r.stderr
    (tmp_path / "afile").write_text("x")
    r = _seatrack("track", "p.csv", "--out", "afile/o.csv", cwd=tmp_path)
    assert r.returncode == 2 and "afile is a file" in r.stderr
    # a failing run leaves the previous output intact and no temporary file
    (tmp_path / "o.csv").write_text("previous\n")
    (tmp_path / "bad.csv").write_text("time_s,range_m,azimuth_deg\n0,100,10\n1,-5,10\n")
    r = _seatrack("track", "bad.csv", "--out", "o.csv", cwd=tmp_path)
    assert r.returncode == 2
    assert (tmp_path / "o.csv").read_text() == "previous\n"
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".o.csv")) == []


def test_two_d_plots_give_empty_z_columns_for_every_method(tmp_path):
    from seatrack.filters.registry import METHODS
    from seatrack.filters.registry import method_class

    _ok_plots(tmp_path / "p.csv")
    for method in METHODS:
        if getattr(method_class(method), "needs_range_rate", False):
            continue  # needs range rate
        r = _seatrack("track", "p.csv", "-m", method, "--out", "o.csv", cwd=tmp_path)
        assert r.returncode == 0, (method, r.stderr)
        rows = list(csv.DictReader(open(tmp_path / "o.csv")))
        assert all(row["z_m"] == row["vz_mps"] == row["std_z_m"] == "" for row in rows), method
        assert rows[0]["status"] == "initiated" and rows[1]["status"] == "updated"


def test_track_label_with_a_comma_is_quoted(tmp_path):
    (tmp_path / "p.csv").write_text(
        'track,time_s,range_m,azimuth_deg\n"a,b",0,5000,30\n"a,b",2,5010,30\n'
    )
    r = _seatrack("track", "p.csv", "--out", "o.csv", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    rows = list(csv.DictReader(open(tmp_path / "o.csv")))
    assert [row["track"] for row in rows] == ["a,b", "a,b"]


def test_list_methods_comes_from_the_registry(tmp_path):
    """``--list-methods`` prints the registry's listing (the reproductions of the sources
    apart, after the methods to pick) and needs no input file; ``--help`` points to it
    (the help names no method list of its own: importing the registry would make
    ``seatrack --help`` slow)."""
    from seatrack.filters.registry import METHODS
    from seatrack.filters.registry import list_methods

    r = _seatrack("track", "--list-methods", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == list_methods().strip()
    picked, sources = r.stdout.split("sources as written")
    assert all(f"  {n} " in sources for n in METHODS if n.endswith("-spec"))
    assert not any(f"  {n} " in picked for n in METHODS if n.endswith("-spec"))
    help_text = " ".join(_seatrack("track", "--help", cwd=tmp_path).stdout.split())
    assert "--list-methods" in help_text
