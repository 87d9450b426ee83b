"""The model library: thesis bounds, inputs, scaling, and the ISO 5R1C steady state by hand."""

import numpy as np
import pytest

from rcengine.building import Building
from rcengine.exceptions import BuildingError, ModelError
from rcengine.models import available_models, get_model
from rcengine.models.iso13790 import AM_PER_AF, AT_PER_AF, H_IS_W_M2K, H_MS_W_M2K

from .synthetic import BUILDING

THESIS_TABLE_2_3 = {
    "r_wall_ext": (0.1, 8.0),
    "r_wall_int": (0.1, 8.0),
    "r_int": (0.01, 3.0),
    "c_wall": (1e4, 1e6),
    "c_air": (1e5, 1e7),
    "c_int": (1e4, 1e6),
    "alpha_wall": (0, 60),
    "alpha_int": (0, 40),
}


def with_surfaces() -> Building:
    data = BUILDING.to_dict()
    data["windows"] = [{"azimuth": 90, "tilt": 90, "area": 45.6}]
    data["walls"] = [{"azimuth": 180, "tilt": 90, "area": 100.0}]
    return Building.from_dict(data)


def test_basic_bounds_are_thesis_table_2_3_for_the_thesis_office():
    net = get_model("basic", BUILDING).compile()
    for name, (lo, hi) in THESIS_TABLE_2_3.items():
        p = net.parameters[name]
        assert (p.lower, p.upper) == pytest.approx((lo, hi)), name
    assert net.input_names == ("t_out", "ghi", "q_hvac", "q_occ", "q_light")
    assert net.state_names == ("wall", "air", "int")


def test_sun_bounds_are_thesis_table_2_4_and_need_surfaces():
    net = get_model("sun", with_surfaces()).compile()
    assert (net.parameters["alpha_wall"].lower, net.parameters["alpha_wall"].upper) == (0.0, 0.25)
    assert (net.parameters["alpha_int"].lower, net.parameters["alpha_int"].upper) == (0.0, 0.95)
    assert "solar_window" in net.input_names and "solar_opaque" in net.input_names
    with pytest.raises(BuildingError, match="windows"):
        get_model("sun", BUILDING)


def test_per_area_scaling_in_matrices():
    net = get_model("basic", BUILDING).compile()
    p = {
        "r_wall_ext": 2.0,
        "r_wall_int": 0.5,
        "r_int": 0.1,
        "c_wall": 1e5,
        "c_air": 1e6,
        "c_int": 2e5,
        "alpha_wall": 10.0,
        "alpha_int": 5.0,
    }
    rc = net.rc_matrices(p)
    np.testing.assert_allclose(rc.capacity[0], [1e5 * 455, 1e6, 2e5 * 560])
    # conductance outdoor→wall is A_wall / r_wall_ext
    assert rc.F[0, 0, 0] == pytest.approx(455 / 2.0)
    assert rc.K[0, 1, 2] == pytest.approx(-1050 / 0.1)


def test_absent_gain_columns_are_left_out_not_zeroed():
    net = get_model("basic", BUILDING, inputs=["t_in", "t_out", "ghi", "q_hvac"]).compile()
    assert net.input_names == ("t_out", "ghi", "q_hvac")


def test_unknown_model_lists_choices():
    with pytest.raises(ModelError, match=r"invalid model 'cube'.*basic"):
        get_model("cube", BUILDING)
    assert {"basic", "sun", "1r1c", "2r2c", "5r1c"} <= set(available_models())


def test_iso_5r1c_steady_state_by_hand():
    """Constant t_out = 0 and q_hvac = Q: the air settles at Q over the network's total UA."""
    net = get_model("5r1c", BUILDING, inputs=["t_out", "ghi", "q_hvac"]).compile()
    af = BUILDING.floor_area
    p = {"r_ve": 2.0, "r_win": 4.0, "r_em": 3.0, "c_m": 1.65e5, "alpha_sol": 0.0}
    h_ve, h_w, h_em = af / 2.0, af / 4.0, af / 3.0
    h_is, h_ms = H_IS_W_M2K * AT_PER_AF * af, H_MS_W_M2K * AM_PER_AF * af
    # air –h_is– surface; surface –h_w– out and –(h_ms in series with h_em)– out; air –h_ve– out.
    h_surface_out = h_w + 1 / (1 / h_ms + 1 / h_em)
    ua = h_ve + 1 / (1 / h_is + 1 / h_surface_out)
    q = 10_000.0
    A, B, C, D = net.state_space(p)
    u = np.array([{"t_out": 0.0, "ghi": 0.0, "q_hvac": q}[n] for n in net.input_names])
    x_ss = np.linalg.solve(A[0], -B[0] @ u)
    assert C[0] @ x_ss + D[0] @ u == pytest.approx(q / ua, rel=1e-9)


@pytest.mark.parametrize("name", ["basic", "1r1c", "2r2c", "5r1c"])
def test_every_model_is_passive_and_heats_up(name):
    net = get_model(name, BUILDING).compile()
    mid = np.sqrt(np.where(net.lower > 0, net.lower, 1e-3) * net.upper)
    A, B, C, D = net.state_space(mid[None, :])
    assert np.all(np.linalg.eigvals(A[0]).real < 0)
    j = net.input_names.index("q_hvac")
    x_ss = np.linalg.solve(A[0], -B[0][:, j])
    assert C[0] @ x_ss + D[0][j] > 0  # heating raises the indoor temperature
