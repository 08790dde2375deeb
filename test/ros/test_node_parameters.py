"""foot_fk_node's parameter ranges (FloatingPointRange, enforced by rclpy), on a node in this
process."""

from __future__ import annotations

import math

import pytest
from rclpy.parameter import Parameter

from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.ros.foot_fk_node import FootFkNode

# The ranges the README and config/params.yaml document (inclusive).
DOCUMENTED_RANGES = {
    "marker_rate_hz": (0.001, 1000.0),
    "max_publish_rate_hz": (0.0, 1_000_000.0),
    "verify_tolerance_m": (1e-12, 1.0),
    "touchdown_force_n": (0.0, 1e6),
    "liftoff_force_n": (0.0, 1e6),
    "gait_phase_timeout_s": (0.001, 3600.0),
}


@pytest.fixture
def node(ros):
    started = FootFkNode(
        context=ros.context, parameter_overrides=[Parameter("enable_verify", value=False)]
    )
    yield started
    started.destroy_node()


def _outside(lowest: float, highest: float) -> list[float]:
    just_below = lowest / 2 if lowest > 0 else -1e-9
    return [just_below, highest * 2, -1.0, math.nan, math.inf, -math.inf]


@pytest.mark.parametrize("name", sorted(DOCUMENTED_RANGES))
def test_values_outside_the_documented_range_are_rejected_naming_the_parameter_and_old_value_kept(
    node, name
):
    old = node.get_parameter(name).value
    for value in _outside(*DOCUMENTED_RANGES[name]):
        result = node.set_parameters([Parameter(name, value=value)])[0]
        assert not result.successful, (name, value)
        assert name in result.reason and "out of range" in result.reason, result.reason
        assert node.get_parameter(name).value == old


@pytest.mark.parametrize("name", sorted(DOCUMENTED_RANGES))
def test_both_bounds_are_accepted(node, name):
    for bound in DOCUMENTED_RANGES[name]:
        result = node.set_parameters([Parameter(name, value=bound)])[0]
        assert result.successful, result.reason
        assert node.get_parameter(name).value == bound


def test_the_settings_follow_accepted_values(node):
    node.set_parameters(
        [Parameter("marker_rate_hz", value=4.0), Parameter("max_publish_rate_hz", value=0.0)]
    )
    assert node._marker_interval_s == 0.25 and node._min_publish_interval_s == 0.0
    node.set_parameters([Parameter("max_publish_rate_hz", value=50.0)])
    assert node._min_publish_interval_s == 0.02


def test_an_out_of_range_value_at_start_is_a_leg_fk_error_naming_the_parameter(ros):
    with pytest.raises(LegFkError, match=r"marker_rate_hz.*out of range"):
        FootFkNode(
            context=ros.context, parameter_overrides=[Parameter("marker_rate_hz", value=0.0)]
        )


def test_preserialized_output_can_be_turned_off_and_on_at_run_time(node):
    assert node._output.preserialized  # on by default (and usable with this rmw)
    assert node.set_parameters([Parameter("preserialized_output", value=False)])[0].successful
    assert not node._output.preserialized
    assert node.set_parameters([Parameter("preserialized_output", value=True)])[0].successful
    assert node._output.preserialized


def _thresholds(node: FootFkNode) -> tuple[float, float]:
    """The node's contact thresholds [N]: touchdown, liftoff."""
    forces = node._forces
    assert forces is not None, node._forces_problem
    return forces.thresholds.touchdown_n, forces.thresholds.liftoff_n


def test_contact_thresholds_default_to_the_weight_and_follow_the_parameters(node):
    forces = node._forces
    assert forces is not None
    weight = forces.estimator.statics.total_mass_kg * 9.80665  # the URDF's masses
    assert _thresholds(node) == pytest.approx((0.08 * weight, 0.04 * weight))
    touchdown = Parameter("touchdown_force_n", value=20.0)
    liftoff = Parameter("liftoff_force_n", value=8.0)
    assert all(r.successful for r in node.set_parameters([touchdown, liftoff]))
    assert _thresholds(node) == (20.0, 8.0)
    # liftoff above touchdown: no forces (a warning, and diagnostics say why) until fixed
    assert node.set_parameters([Parameter("liftoff_force_n", value=30.0)])[0].successful
    assert node._forces is None and "liftoff" in node._forces_problem
    assert node.set_parameters([Parameter("liftoff_force_n", value=0.0)])[0].successful
    assert _thresholds(node) == pytest.approx((20.0, min(0.04 * weight, 20.0)))
    for name, value in (("force_model", "static"), ("contact_rule", "threshold")):
        assert node.set_parameters([Parameter(name, value=value)])[0].successful
        assert node._forces is not None and getattr(node._forces.estimator, name) == value
    assert node.set_parameters([Parameter("force_model", value="guess")])[0].successful
    assert node._forces is None and "force model must be one of" in node._forces_problem
    assert node.set_parameters([Parameter("force_model", value="dynamic")])[0].successful
    assert node.set_parameters([Parameter("publish_forces", value=False)])[0].successful
    assert node._forces_problem == "off"
    assert not node.set_parameters([Parameter("touchdown_force_n", value=-1.0)])[0].successful
