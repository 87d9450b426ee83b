"""The contract CSV (CONTRACT.md §1): every validation rule, its row/column, and the round trip."""

from __future__ import annotations

import io

import numpy as np
import pandas as pd
import pytest

from rcengine.exceptions import DataValidationError
from rcengine.io.timeseries import (
    MAX_PROBLEMS,
    format_times,
    parse_rows,
    read_timeseries,
    validate_frame,
    write_timeseries,
)

HEADER = "time,t_in,t_out,ghi,q_hvac"


def csv(*rows: str, header: str = HEADER) -> io.StringIO:
    return io.StringIO("\n".join([header, *rows]) + "\n")


def quarter_hours(n: int, start: str = "2017-01-09T06:00:00+01:00") -> list[str]:
    times = pd.date_range(pd.Timestamp(start), periods=n, freq="15min")
    return [t.isoformat() for t in times]


def good_rows(n: int) -> list[str]:
    return [f"{t},20.5,3.0,100,1500" for t in quarter_hours(n)]


def problems_of(source, reader=read_timeseries):
    with pytest.raises(DataValidationError) as caught:
        reader(source)
    return caught.value.problems


# --- a valid file -----------------------------------------------------------------------------
def test_valid_file_gives_utc_index_and_float_columns():
    frame = read_timeseries(
        csv(
            "2017-01-09T06:15:00+01:00,20.5,3.1,0,100,7,x",
            "2017-01-09T06:30:00+01:00,20.6,3.2,12.5,-200,,y",
            header=HEADER + ",q_occ,comment",
        )
    )
    assert frame.index.name == "time"
    assert str(frame.index.tz) == "UTC"
    assert frame.index[0] == pd.Timestamp("2017-01-09T05:15:00Z")  # 06:15 at UTC+1
    assert list(frame.columns) == ["t_in", "t_out", "ghi", "q_hvac", "q_occ"]  # comment ignored
    assert all(dtype == np.float64 for dtype in frame.dtypes)
    assert frame.loc["2017-01-09T05:30:00Z", "q_hvac"] == -200.0
    assert np.isnan(frame["q_occ"].iloc[1])  # optional value may be empty


def test_z_and_mixed_offsets_are_the_same_instant():
    frame = read_timeseries(
        csv("2017-07-09T04:00:00Z,20,3,0,0", "2017-07-09T06:15:00+02:00,20,3,0,0")
    )
    assert list(frame.index) == [
        pd.Timestamp("2017-07-09T04:00Z"),
        pd.Timestamp("2017-07-09T04:15Z"),
    ]


# --- columns ----------------------------------------------------------------------------------
def test_missing_required_columns_are_each_named():
    problems = problems_of(csv("2017-01-09T06:15:00+01:00,20.5", header="time,t_in"))
    missing = {p.column for p in problems}
    assert missing == {"t_out", "ghi", "q_hvac"}
    assert all(p.row is None and "is missing" in p.message for p in problems)


def test_misspelt_column_gets_a_hint():
    (problem,) = problems_of(
        csv("2017-01-09T06:15:00+01:00,20,3,0,0", header="time,T_IN,t_out,ghi,q_hvac")
    )
    assert problem.column == "t_in"
    assert "'T_IN'" in problem.message


def test_column_named_twice_is_an_error():
    problems = problems_of(
        csv("2017-01-09T06:15:00+01:00,20,21,3,0,0", header="time,t_in,t_in,t_out,ghi,q_hvac")
    )
    assert [(p.column, "more than once" in p.message) for p in problems] == [("t_in", True)]


# --- time -------------------------------------------------------------------------------------
def time_problem(n: int, row: int, text: str) -> str:
    """The message of the one problem of ``n`` good rows whose row ``row`` has the time ``text``,
    which must be that row's time."""
    rows = good_rows(n)
    rows[row] = f"{text},20,3,0,0"
    (problem,) = problems_of(csv(*rows))
    assert (problem.row, problem.column) == (row, "time")
    return problem.message


def test_unparseable_time_names_row_text_and_line():
    message = time_problem(14, 12, "09/01/2017 09:00")
    assert "'09/01/2017 09:00'" in message
    assert "line 14 of the file" in message  # header is line 1, row 0 line 2


def test_time_without_offset_is_rejected():
    rows = good_rows(3)
    rows[1] = "2017-01-09T06:15:00,20,3,0,0"
    (problem,) = problems_of(csv(*rows))
    assert (problem.row, problem.column) == (1, "time")
    assert "no UTC offset" in problem.message


def test_impossible_date_is_rejected():
    assert "no such time" in time_problem(1, 0, "2017-02-30T00:00:00+01:00")


def test_duplicate_timestamp_names_both_rows():
    rows = good_rows(4)
    rows[3] = rows[1]
    (problem,) = problems_of(csv(*rows))
    assert (problem.row, problem.column) == (3, "time")
    assert "duplicate" in problem.message and "row 1" in problem.message


def test_decreasing_timestamp_names_both_rows():
    rows = good_rows(4)
    rows[2], rows[3] = rows[3], rows[2]
    (problem,) = problems_of(csv(*rows))
    assert (problem.row, problem.column) == (3, "time")
    assert "earlier than row 2" in problem.message


@pytest.mark.parametrize("freq, shown", [("30s", "30 s"), ("2h", "2 h")])
def test_step_outside_60_to_3600_s(freq, shown):
    times = pd.date_range(pd.Timestamp("2017-01-09T06:00+01:00"), periods=5, freq=freq)
    (problem,) = problems_of(csv(*[f"{t.isoformat()},20,3,0,0" for t in times]))
    assert (problem.row, problem.column) == (None, "time")
    assert f"step is {shown}" in problem.message


def test_gaps_are_allowed_mixed_steps_are_not():
    rows = good_rows(8)
    gappy = rows[:3] + rows[5:]  # two quarter-hours missing: a gap
    assert len(read_timeseries(csv(*gappy))) == 6
    rows[5] = "2017-01-09T07:20:00+01:00,20,3,0,0"  # 5 min after the 07:15 row
    problems = problems_of(csv(*rows))
    assert [(p.row, p.column) for p in problems] == [(5, "time"), (6, "time")]
    assert "not a whole multiple of the step 15 min" in problems[0].message


# --- values -----------------------------------------------------------------------------------
def test_non_numeric_value_names_row_column_and_text():
    rows = good_rows(3)
    rows[2] = rows[2].replace(",20.5,", ",warm,")
    rows[1] = rows[1].replace(",3.0,", ',"3,5",')
    problems = problems_of(csv(*rows))
    assert {(p.row, p.column) for p in problems} == {(2, "t_in"), (1, "t_out")}
    by_column = {p.column: p.message for p in problems}
    assert "'warm'" in by_column["t_in"]
    assert "decimal separator" in by_column["t_out"]


def test_t_in_may_be_empty_but_inputs_may_not():
    rows = good_rows(3)
    rows[1] = rows[1].replace(",20.5,", ",,")  # future row: no indoor temperature
    assert np.isnan(read_timeseries(csv(*rows))["t_in"].iloc[1])
    rows[2] = rows[2].replace(",100,", ",,")
    (problem,) = problems_of(csv(*rows))
    assert (problem.row, problem.column) == (2, "ghi")
    assert "needed in every row" in problem.message


def test_empty_columns_optional_dropped_t_in_kept_inputs_rejected():
    rows = [f"{t},,3,0,0," for t in quarter_hours(3)]
    frame = read_timeseries(csv(*rows, header=HEADER + ",wind_speed"))
    assert "wind_speed" not in frame.columns
    assert frame["t_in"].isna().all()
    problems = problems_of(csv(*[f"{t},20,,0,0" for t in quarter_hours(50)]))
    assert [(p.row, p.column) for p in problems] == [(None, "t_out")]  # one, not fifty


def test_physically_impossible_values():
    rows = good_rows(3)
    rows[1] = rows[1].replace(",20.5,", ",500,")
    rows[2] += ",-40"
    problems = problems_of(csv(*rows, header=HEADER + ",q_occ"))
    assert {(p.row, p.column) for p in problems} == {(1, "t_in"), (2, "q_occ")}
    assert any("500 °C is outside" in p.message for p in problems)


def test_cloud_cover_is_a_percentage():
    rows = [f"{r},{c}" for r, c in zip(good_rows(3), ["0", "62.5", "100"], strict=True)]
    assert read_timeseries(csv(*rows, header=HEADER + ",cloud_cover"))["cloud_cover"].tolist() == [
        0.0,
        62.5,
        100.0,
    ]
    rows[1] = rows[1].removesuffix("62.5") + "6.25e2"
    (problem,) = problems_of(csv(*rows, header=HEADER + ",cloud_cover"))
    assert (problem.row, problem.column) == (1, "cloud_cover")
    assert "%" in problem.message


def test_irradiance_noise_clipped_beyond_noise_rejected():
    rows = [f"{t},20,3,{g},0" for t, g in zip(quarter_hours(3), ["-4.5", "0", "250"], strict=True)]
    assert read_timeseries(csv(*rows))["ghi"].tolist() == [0.0, 0.0, 250.0]
    rows[0] = rows[0].replace("-4.5", "-30")
    (problem,) = problems_of(csv(*rows))
    assert (problem.row, problem.column) == (0, "ghi")
    assert "negative" in problem.message


def test_kelvin_is_one_message_per_column():
    n = 500
    kelvin = 273.15 + 10.0 + np.sin(np.arange(n))
    rows = [f"{t},20,{k:.2f},0,0" for t, k in zip(quarter_hours(n), kelvin, strict=True)]
    (problem,) = problems_of(csv(*rows))
    assert (problem.row, problem.column) == (None, "t_out")
    median = np.median(np.round(kelvin, 2))
    assert f"looks like Kelvin (median {median:.1f})" in problem.message
    assert "subtract 273.15" in problem.message


def test_all_problems_are_collected_not_just_the_first():
    rows = good_rows(5)
    rows[1] = "yesterday,20,3,0,0"
    rows[2] = rows[2].replace(",3.0,", ",cold,")
    rows[4] = rows[4].replace(",1500", ",")
    problems = problems_of(csv(*rows))
    assert {(p.row, p.column) for p in problems} == {(1, "time"), (2, "t_out"), (4, "q_hvac")}


def test_problem_list_is_capped():
    rows = [f"{t},x,3,0,0" for t in quarter_hours(3 * MAX_PROBLEMS)]
    problems = problems_of(csv(*rows))
    assert len(problems) == MAX_PROBLEMS + 1
    assert "stopped after" in problems[-1].message
    with pytest.raises(DataValidationError, match=r"and 981 more"):
        read_timeseries(csv(*rows))


# --- the file as a whole ----------------------------------------------------------------------
def test_empty_header_only_unreadable_and_semicolon_files(tmp_path):
    for source, text in [
        (io.StringIO(""), "empty"),
        (csv(), "no data rows"),
        (tmp_path / "absent.csv", "cannot read"),
        (io.StringIO("time;t_in;t_out;ghi;q_hvac\n2017-01-09T06:15:00+01:00;20;3;0;0\n"), "';'"),
    ]:
        (problem,) = problems_of(source)
        assert problem.row is None and text in problem.message


def test_blank_lines_keep_line_numbers_and_trailing_ones_are_ignored():
    rows = good_rows(4)
    assert len(read_timeseries(io.StringIO("\n".join([HEADER, *rows]) + "\n\n\n"))) == 4
    rows[2] = rows[2].replace(",20.5,", ",warm,")
    blank, bad = problems_of(csv(rows[0], "", *rows[1:]))
    assert (blank.row, blank.column) == (1, None)
    assert "empty row" in blank.message and "line 3 of the file" in blank.message
    assert (bad.row, bad.column) == (3, "t_in")  # rows after the blank line keep their numbers
    assert "line 5 of the file" in bad.message


# --- JSON rows --------------------------------------------------------------------------------
def test_json_rows_accept_numbers_numeric_strings_and_null():
    rows = [
        {
            "time": "2017-01-09T06:15:00+01:00",
            "t_in": 20.5,
            "t_out": "3.1",
            "ghi": 0,
            "q_hvac": 100,
        },
        {"time": "2017-01-09T06:30:00+01:00", "t_in": None, "t_out": 3.2, "ghi": 0, "q_hvac": 1},
        {"time": "2017-01-09T06:45:00+01:00", "t_out": 3.3, "ghi": 0, "q_hvac": 1},  # no t_in key
    ]
    frame = parse_rows(rows)
    expected = read_timeseries(
        csv(
            "2017-01-09T06:15:00+01:00,20.5,3.1,0,100",
            "2017-01-09T06:30:00+01:00,,3.2,0,1",
            "2017-01-09T06:45:00+01:00,,3.3,0,1",
        )
    )
    pd.testing.assert_frame_equal(frame, expected)


def test_json_rows_reject_booleans_non_objects_and_bad_values():
    good = {"time": "2017-01-09T06:15:00+01:00", "t_in": 20, "t_out": 3, "ghi": 0, "q_hvac": 0}
    (problem,) = problems_of([good, "not a row"], parse_rows)
    assert problem.row == 1
    second = {**good, "time": "2017-01-09T06:30:00+01:00", "q_hvac": True, "t_in": "hot"}
    problems = problems_of([good, second], parse_rows)
    assert {(p.row, p.column) for p in problems} == {(1, "q_hvac"), (1, "t_in")}
    assert all("line" not in p.message for p in problems)  # rows of a list have no lines


def test_validate_frame_takes_tz_aware_times():
    times = pd.date_range("2017-01-09T06:00+01:00", periods=3, freq="15min")
    raw = pd.DataFrame({"time": times, "t_in": 20.0, "t_out": 3.0, "ghi": 0.0, "q_hvac": 0.0})
    assert validate_frame(raw).index[0] == pd.Timestamp("2017-01-09T05:00Z")


# --- writing ----------------------------------------------------------------------------------
def test_format_times_uses_the_zone_offset_of_each_instant():
    index = pd.DatetimeIndex(["2017-01-09T05:15:00Z", "2017-07-09T04:15:00Z"])
    assert format_times(index, "Europe/Rome") == [
        "2017-01-09T06:15:00+01:00",
        "2017-07-09T06:15:00+02:00",
    ]
    assert format_times(index[:1], "UTC") == ["2017-01-09T05:15:00+00:00"]
    with pytest.raises(ValueError, match="tz-aware"):
        format_times(pd.DatetimeIndex(["2017-01-09T05:15:00"]), "UTC")


def test_write_then_read_gives_the_same_frame():
    rows = [
        f"{t},{20 + i / 3},{3 - i / 7},{i * 1.1},{1000 / (i + 1)},{'' if i % 2 else 0.1 * i}"
        for i, t in enumerate(quarter_hours(20))
    ]
    rows[4] = rows[4].replace(rows[4].split(",")[1], "", 1)  # an empty t_in
    frame = read_timeseries(csv(*rows, header=HEADER + ",wind_speed"))
    buffer = io.StringIO()
    write_timeseries(frame, buffer, "Europe/Rome")
    assert buffer.getvalue().splitlines()[1].startswith("2017-01-09T06:00:00+01:00,")
    back = read_timeseries(io.StringIO(buffer.getvalue()))
    pd.testing.assert_frame_equal(back, frame)


def test_errors_cross_a_process_boundary_whole():
    """A job's error is pickled back from its worker: it listed each character of its message
    as a problem."""
    import pickle

    from rcengine.exceptions import BuildingError, DataValidationError, Problem

    error = DataValidationError([Problem(96, "q_occ", "input value missing")] * 25)
    back = pickle.loads(pickle.dumps(error))
    assert str(back) == str(error) and back.problems == error.problems
    building = pickle.loads(pickle.dumps(BuildingError("field 'volume' ...", "volume")))
    assert (str(building), building.field) == ("field 'volume' ...", "volume")
