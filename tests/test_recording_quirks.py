"""Measurement files as real rigs write them: other dialects, units, rasters, clocks and flaws.

Each variant of a small synthetic clutch step either loads as the plain rig-style CSV does (channel for channel) or is
refused in one line naming the file and the channel.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy import io as sio

from wetclutch.errors import WetclutchError
from wetclutch.ident import play
from wetclutch.ident import recordings as channels
from wetclutch.rig.files import read_columns, read_measurement

RPM = 60 / (2 * np.pi)


def step_frame(dt: float = 1e-3, t_end: float = 2.0, seed: int = 0) -> pd.DataFrame:
    """A clutch step in the rig's names and SI units: command up at 1 s, pressure and torque following."""
    t = np.arange(round(t_end / dt) + 1) * dt
    rng = np.random.default_rng(seed)
    up = t >= 1.0
    p = np.where(up, 1.6e5 * (1 - np.exp(-(t - 1.0) / 0.05)), 0.0) + rng.normal(0, 2e3, t.size)
    return pd.DataFrame({"time": t, "u": np.where(up, 1.8, 0.2), "p_clutch": p,
                         "T_r": np.where(up, 30.0 * (1 - np.exp(-(t - 1.0) / 0.1)), 0.0) + rng.normal(0, 0.5, t.size),
                         "omega_p": 150.0 - 5.0 * t, "omega_1": np.where(up, 40.0 * (t - 1.0), 0.0),
                         "omega_r": np.where(up, 20.0 * (t - 1.0), 0.0), "omega_s": np.where(up, 20.0 * (t - 1.0), 0.0),
                         "oil_temp": 41.0 + rng.normal(0, 0.2, t.size)})


@pytest.fixture
def plain(tmp_path) -> channels.Recording:
    frame = step_frame()
    (tmp_path / "plain").mkdir()
    frame.to_csv(tmp_path / "plain" / "run.csv", index=False, float_format="%.12g")
    return channels.load(tmp_path / "plain" / "run.csv")


def assert_same(got: channels.Recording, want: channels.Recording) -> None:
    assert (got.experiment, got.config, got.input_mode) == (want.experiment, want.config, want.input_mode)
    assert sorted(got.data) == sorted(want.data)
    for ch, x in want.data.items():
        np.testing.assert_allclose(got.data[ch], x, rtol=1e-9, atol=1e-9 * max(1.0, np.max(np.abs(x))), err_msg=ch)


def refused(path: Path, fragment: str, cmap: dict | None = None) -> str:
    with pytest.raises(WetclutchError) as info:
        channels.load(path, cmap)
    msg = str(info.value)
    assert fragment in msg and str(path) in msg and "\n" not in msg, msg
    return msg


# ---------------------------------------------------------------- CSV dialects


def _german(frame: pd.DataFrame) -> bytes:
    """A German Excel export: cp1252, semicolons, decimal commas, a unit row in bar, U/min and °C, time in ms."""
    eng = frame.assign(time=frame.time * 1e3, p_clutch=frame.p_clutch / 1e5,
                       **{c: frame[c] * RPM for c in ("omega_p", "omega_1", "omega_r", "omega_s")})
    units = "ms;V;bar;Nm;U/min;U/min;U/min;U/min;°C\n"
    return (";".join(eng.columns) + "\n" + units
            + eng.to_csv(sep=";", decimal=",", index=False, header=False, float_format="%.12g")).encode("cp1252")


@pytest.mark.parametrize("variant", ["semicolon_decimal_comma", "tab", "space_after_comma", "hash_preamble",
                                     "unit_row", "bracketed_unit_row", "german_excel", "trailing_separator"])
def test_csv_dialects_read_like_the_plain_csv(plain, tmp_path, variant):
    frame = step_frame()
    text = frame.to_csv(index=False, float_format="%.12g")
    path = tmp_path / f"{variant}.csv"
    if variant == "semicolon_decimal_comma":
        path.write_text(frame.to_csv(sep=";", decimal=",", index=False, float_format="%.12g"))
    elif variant == "tab":
        path.write_text(frame.to_csv(sep="\t", index=False, float_format="%.12g"))
    elif variant == "space_after_comma":
        path.write_text(text.replace(",", ", "))
    elif variant == "hash_preamble":
        path.write_text("# rig 3, bench B\n# 2024-05-01, operator: K.\n" + text)
    elif variant in ("unit_row", "bracketed_unit_row"):
        eng = frame.assign(time=frame.time * 1e3, p_clutch=frame.p_clutch / 1e5, omega_p=frame.omega_p * RPM)
        units = ["ms", "V", "bar", "N m", "rpm", "rad/s", "rad/s", "rad/s", "C"]
        units = [f"[{u}]" for u in units] if variant == "bracketed_unit_row" else units
        path.write_text(",".join(eng.columns) + "\n" + ",".join(units) + "\n"
                        + eng.to_csv(index=False, header=False, float_format="%.12g"))
    elif variant == "german_excel":
        path.write_bytes(_german(frame))
    else:  # Excel ends each row with its separator
        path.write_text("".join(line + ";\n" for line in frame.to_csv(sep=";", index=False).splitlines()))
    assert_same(channels.load(path), plain)


def test_an_unrelated_text_column_is_left_out_but_text_in_a_channel_is_named(plain, tmp_path):
    frame = step_frame().assign(status=lambda f: np.where(f.index % 7, "OK", "WARN"), gear=3)
    frame.to_csv(tmp_path / "extra.csv", index=False, float_format="%.12g")
    rec = channels.load(tmp_path / "extra.csv")
    assert_same(rec, plain)
    frame = frame.astype({"p_clutch": object})
    frame.loc[1234, "p_clutch"] = "OVL"
    frame.to_csv(tmp_path / "bad.csv", index=False)
    refused(tmp_path / "bad.csv", "column 'p_clutch' is not numeric (line 1236: 'OVL')")
    # a column the map reads is a channel too
    refused(tmp_path / "extra.csv", "column 'status' is not numeric (line 2: 'WARN')", {"oil_temp": {"name": "status"}})
    # the reader alone, asked for everything, still refuses text
    with pytest.raises(WetclutchError, match="column 'status' is not numeric"):
        read_measurement(tmp_path / "extra.csv")


def test_decimal_commas_in_a_comma_separated_file_are_refused_clearly(tmp_path):
    text = step_frame().to_csv(index=False, float_format="%.6f").replace(".", ",")
    (tmp_path / "run.csv").write_text(",".join(step_frame().columns) + "\n" + text.split("\n", 1)[1])
    refused(tmp_path / "run.csv", "rows have more cells than the header has names (decimal commas")


def test_a_missing_channel_names_the_columns_the_file_has(tmp_path):
    step_frame().rename(columns={"time": "time [s]"}).to_csv(tmp_path / "run.csv", index=False)
    refused(tmp_path / "run.csv", "required channel 'time' missing (the file has 'time [s]', 'u', 'p_clutch'")


# ---------------------------------------------------------------- MATLAB


def test_a_mat_struct_of_vectors_reads_like_the_csv(plain, tmp_path):
    frame = step_frame()
    fields = {c: frame[c].to_numpy() for c in frame.columns}
    sio.savemat(tmp_path / "run.mat", {"meas": {**fields, "p_clutch": frame.p_clutch.to_numpy() / 1e5,
                                                "units": {"p_clutch": "bar"}}, "info": "bench B"})
    assert_same(channels.load(tmp_path / "run.mat"), plain)


def test_a_mat_v73_file_is_refused_naming_the_format(tmp_path):
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, HDF5 schema 1.00 .".ljust(124, b" ") + b"\x00\x02IM"
    (tmp_path / "run.mat").write_bytes(header.ljust(512, b"\0") + b"\x89HDF\r\n\x1a\n" + bytes(64))
    refused(tmp_path / "run.mat", "MATLAB v7.3 (HDF5)")


# ---------------------------------------------------------------- MDF with several rasters


def _mdf(path: Path, groups: list[list[tuple[str, np.ndarray, np.ndarray]]]) -> None:
    from asammdf import MDF, Signal

    with MDF(version="4.10") as mdf:
        for g in groups:
            mdf.append([Signal(x, t, name=name, unit="C" if name == "oil_temp" else "") for name, t, x in g])
        mdf.save(path, overwrite=True)


def test_mdf_channels_on_other_rasters_are_interpolated_onto_the_main_one(plain, tmp_path):
    f = step_frame()
    t = f.time.to_numpy()
    fast = [(c, t, f[c].to_numpy()) for c in f.columns if c not in ("time", "oil_temp")]
    slow_t = t[::100]
    slow_temp = [("oil_temp", slow_t, np.interp(slow_t, t, f.oil_temp.to_numpy()))]
    can = [(n, t[::10], np.full(t[::10].size, v)) for n, v in (("gear", 3.0), ("n_eng", 2000.0), ("pedal", 0.1))]
    _mdf(tmp_path / "temp_first.mf4", [slow_temp, fast])
    _mdf(tmp_path / "can_first.mf4", [can, fast + [("oil_temp", t, f.oil_temp.to_numpy())]])
    a = channels.load(tmp_path / "temp_first.mf4")
    np.testing.assert_allclose(a.data["oil_temp"], np.interp(t, slow_t, slow_temp[0][2]))
    assert_same(channels.Recording(a.path, {**a.data, "oil_temp": plain.data["oil_temp"]}, a.experiment, a.config,
                                   a.input_mode), plain)
    assert_same(channels.load(tmp_path / "can_first.mf4"), plain)
    np.testing.assert_allclose(read_columns(tmp_path / "can_first.mf4")[0]["gear"], 3.0)


def test_an_mdf_raster_that_does_not_cover_the_record_is_refused_only_where_needed(plain, tmp_path):
    f = step_frame()
    t = f.time.to_numpy()
    late = t[t >= 1.5][::50]
    fast = [(c, t, f[c].to_numpy()) for c in f.columns if c not in ("time", "oil_temp")]
    _mdf(tmp_path / "late_temp.mf4", [fast, [("oil_temp", late, np.full(late.size, 41.0))]])
    refused(tmp_path / "late_temp.mf4", "channel 'oil_temp' (channel group 1, another raster than the time base's "
                                        "group 0) covers t = 1.5..2 s, not the record's t = 0..2 s")
    _mdf(tmp_path / "late_aux.mf4", [fast + [("oil_temp", t, f.oil_temp.to_numpy())],
                                     [("aux", late, np.ones(late.size))]])
    assert_same(channels.load(tmp_path / "late_aux.mf4"), plain)


# ---------------------------------------------------------------- clocks, rates and gaps


@pytest.mark.parametrize(("scale", "fragment"), [
    (1e3, "a sample rate of 1 Hz below the 50 Hz identification needs; is its unit right? (a channel map gives it: "
          'time = { name = "...", unit = "ms" })'),
    (1e-3, 'a sample rate of 1e+06 Hz above 200000 Hz; is its unit right? (a channel map gives it: time = { name = '
           '"...", unit = "s" })'),
])
def test_a_time_column_in_the_wrong_unit_is_refused(tmp_path, scale, fragment):
    step_frame().assign(time=lambda f: f.time * scale).to_csv(tmp_path / "run.csv", index=False)
    refused(tmp_path / "run.csv", f"channel 'time' steps {1e-3 * scale:.3g} s, {fragment}")


def test_a_record_too_short_to_identify_is_refused(tmp_path):
    step_frame().iloc[990:1030].to_csv(tmp_path / "run.csv", index=False)
    refused(tmp_path / "run.csv", "channel 'time' spans 0.039 s, too short to identify anything (at least 0.1 s)")


def test_a_lost_sample_is_interpolated_but_a_gap_is_refused(plain, tmp_path):
    f = step_frame()
    f.drop(index=[700, 1500, 1501]).to_csv(tmp_path / "lost.csv", index=False, float_format="%.12g")
    rec = channels.load(tmp_path / "lost.csv")
    assert rec.t.size == plain.t.size and np.allclose(np.diff(rec.t), 1e-3)
    np.testing.assert_allclose(rec.data["omega_p"], plain.data["omega_p"], atol=1e-9)
    f.drop(index=range(1200, 1250)).to_csv(tmp_path / "gap.csv", index=False)
    refused(tmp_path / "gap.csv", "channel 'time' has a gap of 0.051 s after t = 1.199 s (about 50 samples of "
                                  "0.001 s missing; 2 in a row are interpolated)")


@pytest.mark.parametrize("start", [1.7e9, -3.0, 3600.0])
def test_a_clock_far_from_zero_counts_from_the_first_sample(plain, tmp_path, start):
    step_frame().assign(time=lambda f: f.time + start).to_csv(tmp_path / "run.csv", index=False, float_format="%.17g")
    rec = channels.load(tmp_path / "run.csv")
    assert rec.t[0] == 0.0
    np.testing.assert_allclose(rec.t, plain.t, atol=1e-6)
    for ch in ("u", "p_clutch", "T_r"):
        np.testing.assert_allclose(rec.data[ch], plain.data[ch], rtol=1e-9, atol=1e-6)
    # the valve's play is found by replaying the command from time 0: a clock before it broke the replay, a clock
    # far after it made the replay as long as the clock (days for an absolute one)
    u = play.command(rec)
    assert u.time[0] == 0.0 and u.time[-1] < 2.0


def test_a_clock_near_zero_keeps_the_files_time(tmp_path):
    step_frame().assign(time=lambda f: f.time + 12.5).to_csv(tmp_path / "run.csv", index=False)
    assert channels.load(tmp_path / "run.csv").t[0] == 12.5


# ---------------------------------------------------------------- command line


def _cli_files(tmp_path: Path) -> dict[str, Path]:
    f = step_frame()
    files = {"gap": f.drop(index=range(1200, 1250)), "ms": f.assign(time=f.time * 1e3)}
    out = {}
    for name, frame in files.items():
        (tmp_path / name).mkdir()
        frame.to_csv(out.setdefault(name, tmp_path / name / "measured.csv"), index=False)
        (tmp_path / name / "meta.json").write_text(json.dumps({"experiment": "step"}))
    return out


@pytest.mark.parametrize(("name", "fragment"), [("gap", "channel 'time' has a gap of 0.051 s"),
                                                ("ms", "a sample rate of 1 Hz below the 50 Hz")])
def test_cli_identify_refuses_wrong_clocks_in_one_line(tmp_path, cli_refuses, name, fragment):
    path = _cli_files(tmp_path)[name]
    r = cli_refuses(["identify", str(path)], fragment, tmp_path / "out")
    assert str(path) in r.stderr
