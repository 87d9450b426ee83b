"""RC network compilation against matrices written out by hand."""

import numpy as np
import pytest

from rcengine.exceptions import ModelError
from rcengine.network import Parameter, RCNetwork


def two_node() -> RCNetwork:
    net = RCNetwork("2R2C")
    for name in ("r1", "r2", "c1", "c2", "g"):
        net.add_parameter(Parameter(name, "-", 1e-6, 1e9))
    net.add_capacitor("wall", "c1", factor=10.0)  # C = 10·c1
    net.add_capacitor("air", "c2")
    net.add_resistor("t_out", "wall", "r1", factor=0.5)  # R = 0.5·r1
    net.add_resistor("wall", "air", "r2")
    net.add_heat_input("ghi", "wall", "g")
    net.add_heat_input("q_hvac", "air")
    net.set_output("air")
    return net


def test_compiled_matrices_match_hand_written_balances():
    r1, r2, c1, c2, g = 0.02, 0.01, 3e5, 2e6, 7.0
    A, B, C, D = two_node().compile().state_space({"r1": r1, "r2": r2, "c1": c1, "c2": c2, "g": g})
    R1, C1 = 0.5 * r1, 10.0 * c1
    # C1 dTw/dt = (t_out − Tw)/R1 + (Ta − Tw)/r2 + g·ghi ;  c2 dTa/dt = (Tw − Ta)/r2 + q_hvac
    A_hand = np.array([[-(1 / R1 + 1 / r2) / C1, 1 / (r2 * C1)], [1 / (r2 * c2), -1 / (r2 * c2)]])
    B_hand = np.array([[1 / (R1 * C1), g / C1, 0.0], [0.0, 0.0, 1 / c2]])
    np.testing.assert_allclose(A[0], A_hand, rtol=1e-12)
    np.testing.assert_allclose(B[0], B_hand, rtol=1e-12)
    np.testing.assert_array_equal(C[0], [0.0, 1.0])
    np.testing.assert_array_equal(D[0], [0.0, 0.0, 0.0])


def test_input_order_and_shared_signal():
    net = two_node()
    net.add_heat_input("ghi", "air", 0.25)  # the same signal into a second node, fixed gain
    cn = net.compile()
    assert cn.input_names == ("t_out", "ghi", "q_hvac")
    _, B, _, _ = cn.state_space(np.ones((1, 5)))
    assert B[0, 1, 1] == pytest.approx(0.25 / 1.0)


def test_population_axis():
    cn = two_node().compile()
    theta = np.array([[0.02, 0.01, 3e5, 2e6, 7.0], [0.04, 0.01, 3e5, 2e6, 7.0]])
    A, _, _, _ = cn.state_space(theta)
    assert A.shape == (2, 2, 2)
    assert A[1, 0, 0] > A[0, 0, 0]  # doubled outer resistance couples less to outdoors


def test_massless_node_is_eliminated_exactly():
    # t_out —R1— s (massless) —R2— air (C), heat q into s.
    # Then s = (t_out/R1 + T/R2 + q)/(1/R1+1/R2)
    # and C dT/dt = (s − T)/R2 = (t_out − T)/(R1+R2) + q·R1/(R1+R2).
    net = RCNetwork("massless")
    net.add_capacitor("air", 1e6)
    net.add_node("s")
    net.add_resistor("t_out", "s", 0.01)
    net.add_resistor("s", "air", 0.03)
    net.add_heat_input("q", "s")
    net.set_output("s")
    A, B, C, D = net.compile().state_space(np.zeros((1, 0)))
    np.testing.assert_allclose(A[0], [[-1 / (0.04 * 1e6)]])
    np.testing.assert_allclose(B[0], [[1 / (0.04 * 1e6), 0.01 / 0.04 / 1e6]])
    # output s = (t_out/R1 + T/R2 + q) / (1/R1 + 1/R2)
    g = 1 / 0.01 + 1 / 0.03
    np.testing.assert_allclose(C[0], [(1 / 0.03) / g])
    np.testing.assert_allclose(D[0], [(1 / 0.01) / g, 1 / g])


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda n: n.add_capacitor("x", "missing"), "unknown parameter 'missing'"),
        (lambda n: n.add_capacitor("wall", 1.0), "node 'wall' already exists"),
        (lambda n: n.add_heat_input("q", "nowhere"), "unknown node 'nowhere'"),
        (lambda n: n.add_resistor("wall", "wall", 1.0), "to itself"),
        (lambda n: n.add_capacitor("x", -1.0), "finite and ≥ 0"),
    ],
)
def test_construction_errors(build, message):
    with pytest.raises(ModelError, match=message):
        build(two_node())


def test_floating_node_is_rejected():
    net = two_node()
    net.add_capacitor("island", 1.0)
    with pytest.raises(ModelError, match="no resistive path"):
        net.compile()


def test_missing_output_and_parameters():
    net = RCNetwork("x")
    net.add_capacitor("a", 1.0)
    net.add_resistor("a", "t_out", 1.0)
    with pytest.raises(ModelError, match="no output"):
        net.compile()
    with pytest.raises(ModelError, match="missing parameter"):
        two_node().compile().as_theta({"r1": 1.0})


def test_extension_leaves_original_untouched():
    base = two_node()
    extended = base.copy("extended")
    extended.add_capacitor("emitter", 1e5)
    extended.add_resistor("emitter", "air", 0.01)
    assert base.compile().n_states == 2
    assert extended.compile().n_states == 3


def test_fixed_parameters_leave_the_fit_and_a_zero_gain_leaves_its_signal():
    values = {"r1": 0.02, "r2": 0.01, "c1": 3e5, "c2": 2e6, "g": 7.0}
    net = two_node()
    fixed = net.fixed({"c1": 3e5, "g": 0.0}, "2R2C without sun")
    assert fixed.name == "2R2C without sun"
    assert set(fixed.parameters) == {"r1", "r2", "c2"}
    compiled = fixed.compile()
    assert compiled.input_names == ("t_out", "q_hvac")  # the sun's input had gain 0
    A, _, _, _ = compiled.state_space({k: values[k] for k in ("r1", "r2", "c2")})
    A_free, _, _, _ = net.compile().state_space(values)
    np.testing.assert_allclose(A, A_free, rtol=1e-12)  # c1 fixed at the value it had
    assert set(net.parameters) == set(values)  # the original is untouched
    with pytest.raises(ModelError, match="no parameter"):
        net.fixed({"c_mass": 1.0})


def with_emitter() -> RCNetwork:
    """``two_node`` with q_hvac reaching the air through an emitter of capacity ce behind re."""
    net = two_node()
    net.add_parameter(Parameter("ce", "J/K", 0.0, 1e6))
    net.add_parameter(Parameter("re", "K/W", 0.0, 1.0))
    net.add_capacitor("emitter", "ce")
    net.add_resistor("emitter", "air", "re")
    net.move_heat_input("q_hvac", "air", "emitter")
    return net


def test_a_capacity_fixed_at_zero_is_a_massless_node_and_a_zero_resistance_joins_it():
    """C = 0 is the massless node of the same network (Kron-reduced); joined to the air by
    r = 0 as well, the emitter is gone and q_hvac enters the air: the network without it."""
    values = {"r1": 0.02, "r2": 0.01, "c1": 3e5, "c2": 2e6, "g": 7.0}
    massless = with_emitter().fixed({"ce": 0.0})
    assert massless.states == ["wall", "air"] and massless.massless == ["emitter"]
    by_hand = two_node()
    by_hand.add_parameter(Parameter("re", "K/W", 0.0, 1.0))
    by_hand.add_node("emitter")
    by_hand.add_resistor("emitter", "air", "re")
    by_hand.move_heat_input("q_hvac", "air", "emitter")
    for a, b in zip(
        massless.compile().state_space({**values, "re": 0.05}),
        by_hand.compile().state_space({**values, "re": 0.05}),
        strict=True,
    ):
        np.testing.assert_allclose(a, b, rtol=1e-12)
    joined = with_emitter().fixed({"ce": 0.0, "re": 0.0})
    assert joined.nodes == ["wall", "air"]
    for a, b in zip(
        joined.compile().state_space(values), two_node().compile().state_space(values), strict=True
    ):
        np.testing.assert_allclose(a, b, rtol=1e-12)


def test_a_zero_resistance_between_two_capacities_or_to_a_boundary_is_refused():
    with pytest.raises(ModelError, match="both have heat capacity"):
        with_emitter().fixed({"re": 0.0})
    with pytest.raises(ModelError, match="prescribed temperature"):
        two_node().fixed({"r1": 0.0, "c1": 0.0})


def test_a_node_cut_off_by_an_open_circuit_leaves_with_the_heat_into_it():
    values = {"r1": 0.02, "r2": 0.01, "c1": 3e5, "c2": 2e6, "g": 7.0}
    net = two_node()
    net.add_parameter(Parameter("cm", "J/K", 0.0, 1e7))
    net.add_parameter(Parameter("rm", "K/W", 1e-3, 1.0))
    net.add_capacitor("mass", "cm")
    net.add_resistor("mass", "air", "rm")
    net.add_heat_input("q_sun_mass", "mass")
    cut = net.fixed({"rm": np.inf})
    assert cut.states == ["wall", "air"] and set(cut.parameters) == set(values)
    assert cut.compile().input_names == two_node().compile().input_names
    A, B, _, _ = cut.compile().state_space(values)
    A_none, B_none, _, _ = two_node().compile().state_space(values)
    np.testing.assert_allclose(A, A_none, rtol=1e-12)
    np.testing.assert_allclose(B, B_none, rtol=1e-12)


def test_a_resistor_fixed_at_infinity_is_an_open_circuit_and_its_boundary_leaves():
    """A floor to the ground fixed open (r = ∞) is the network without that path: same
    matrices, and the ground temperature is no longer an input."""
    net = two_node()
    net.add_parameter(Parameter("r_floor", "m²K/W", 0.1, 20.0))
    net.add_resistor("t_ground", "wall", "r_floor")
    opened = net.fixed({"r_floor": np.inf})
    assert "t_ground" not in opened.compile().input_names
    values = {"r1": 0.02, "r2": 0.01, "c1": 3e5, "c2": 2e6, "g": 7.0}
    A, B, _, _ = opened.compile().state_space(values)
    A_none, B_none, _, _ = two_node().compile().state_space(values)
    np.testing.assert_allclose(A, A_none, rtol=1e-12)
    np.testing.assert_allclose(B, B_none, rtol=1e-12)
    with pytest.raises(ModelError, match="finite"):
        net.fixed({"c1": np.inf})


def test_a_branch_an_open_circuit_cuts_off_leaves_whole():
    """A floor fixed open (r = ∞) cuts off the soil layer behind it: the soil's capacity, its
    own resistor to the ground, the heat into it and the ground temperature all leave, since
    nothing there can reach the output any more; the network is the one without the floor."""
    net = two_node()
    net.add_parameter(Parameter("r_floor", "m²K/W", 0.1, 20.0))
    net.add_parameter(Parameter("d_soil", "m", 0.05, 6.0))
    net.add_parameter(Parameter("q_ground", "W/m²", -20.0, 60.0))
    net.add_capacitor("soil", "d_soil", factor=2e6)
    net.add_resistor("wall", "soil", "r_floor")
    net.add_resistor("soil", "t_ground", "d_soil", factor=0.5)
    net.add_heat_input("unit", "soil", "q_ground")
    opened = net.fixed({"r_floor": np.inf, "q_ground": 0.0})
    assert opened.states == two_node().states and "d_soil" not in opened.parameters
    assert opened.compile().input_names == two_node().compile().input_names
    values = {"r1": 0.02, "r2": 0.01, "c1": 3e5, "c2": 2e6, "g": 7.0}
    A, B, _, _ = opened.compile().state_space(values)
    A_none, B_none, _, _ = two_node().compile().state_space(values)
    np.testing.assert_allclose(A, A_none, rtol=1e-12)
    np.testing.assert_allclose(B, B_none, rtol=1e-12)
