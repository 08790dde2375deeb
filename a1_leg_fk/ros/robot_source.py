"""Where a node's robot comes from: the model parameters and the ``robot_description`` topic.

:class:`RobotSource` is the one mechanism ``foot_fk_node`` and ``foot_ik_node`` share. It declares
the model parameters, follows the ``robot_description`` topic the way RViz, ros2_control and
MoveIt do (``std_msgs/msg/String``, reliable, transient local, keep last 1, so a description
published before the node started still arrives), and decides which description wins:

1. an explicitly set ``robot_description`` or ``urdf_file`` parameter (the topic is then ignored,
   logged once);
2. otherwise the latest description from the topic;
3. otherwise the embedded A1, until one arrives.

Every description, from a parameter or the topic, goes through
:func:`a1_leg_fk.kinematics.robot_config.load_robot` (size cap, entity refusal, leg discovery,
``foot_links``, ``joint_aliases``). An accepted one is handed to the node's ``on_change``; a
rejected one is logged with its reason, reported by :attr:`RobotSource.topic_status`, and the old
model stays. The same text published again (as robot_state_publisher does on parameter changes)
does not reload.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import cast

from rcl_interfaces.msg import (
    FloatingPointRange,
    ParameterDescriptor,
    ParameterType,
    SetParametersResult,
)
from rclpy.exceptions import InvalidParameterValueException, ParameterUninitializedException
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import String

from a1_leg_fk.kinematics.robot_config import RobotConfig, load_robot
from a1_leg_fk.model.legs import FOOT_NAME_SUFFIXES
from a1_leg_fk.model.urdf import LegFkError
from a1_leg_fk.ros.guarded_input import GuardedInputs, message_reader

DESCRIPTION_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
"""robot_state_publisher's QoS for ``robot_description``: a late subscriber gets the latest one."""


class ParameterChoiceError(Exception):
    """A string parameter given at start outside its choices: a usage error (one line, exit 2)."""


@dataclass(frozen=True)
class ParameterSpec:
    """A parameter a node declares: name, default (``None``: a string array with no value until
    one is given, since ROS cannot type ``[]``), type, description, whether it is read-only, and
    for a double the inclusive ``(lowest, highest)`` range rclpy enforces on every value (NaN is
    outside every range); the description should state the range. A string's ``choices`` (none:
    any) are checked when it is declared (:class:`ParameterChoiceError`); such a parameter is
    read-only.
    """

    name: str
    default: object
    type: int
    description: str
    read_only: bool = False
    value_range: tuple[float, float] | None = None
    choices: tuple[str, ...] = ()

    def declare(self, node: Node) -> None:
        """Declare the parameter on ``node``; a value given at start (``-p``, a params file) that
        is out of range raises :class:`LegFkError` with rclpy's reason, one not among the
        ``choices`` :class:`ParameterChoiceError`.
        """
        descriptor = ParameterDescriptor(description=self.description, read_only=self.read_only)
        if self.value_range is not None:
            lowest, highest = self.value_range
            descriptor.floating_point_range = [
                FloatingPointRange(from_value=lowest, to_value=highest)
            ]
        if self.default is None:
            node.declare_parameter(self.name, Parameter.Type.STRING_ARRAY, descriptor)
            return
        descriptor.type = self.type
        if self.choices:
            descriptor.additional_constraints = f"one of {', '.join(self.choices)}"
        try:
            value = node.declare_parameter(self.name, self.default, descriptor).value
        except InvalidParameterValueException as error:
            raise LegFkError(f"parameter {self.name}: {error}") from error
        if self.choices and value not in self.choices:
            raise ParameterChoiceError(
                f"parameter {self.name} must be one of {', '.join(self.choices)}: {value!r}"
            )


def parameter_value(node: Node, name: str) -> object:
    """A parameter's value; ``[]`` for a string array that was never given one."""
    try:
        return node.get_parameter(name).value
    except ParameterUninitializedException:
        return []


def parameter_values(
    node: Node, names: Sequence[str], changes: Mapping[str, object]
) -> dict[str, object]:
    """The values of ``node``'s parameters ``names``: those in ``changes`` (being set, not stored
    yet) over the stored ones (:func:`parameter_value`).
    """
    return {name: changes.get(name, parameter_value(node, name)) for name in names}


def string_list(value: object) -> list[str]:
    """A string-array parameter's value (rclpy gives a list of str, ``[]`` when unset) as a
    list.
    """
    return list(cast("Sequence[str]", value))


EXPLICIT_PARAMETERS = ("robot_description", "urdf_file")
MODEL_PARAMETERS = (*EXPLICIT_PARAMETERS, "foot_links", "joint_aliases")
PARAMETERS = (
    ParameterSpec(
        "robot_description",
        "",
        ParameterType.PARAMETER_STRING,
        "URDF XML of the robot; when set (or urdf_file is), the robot_description topic is "
        "ignored",
    ),
    ParameterSpec(
        "urdf_file",
        "",
        ParameterType.PARAMETER_STRING,
        "Path of a URDF file, used when robot_description is empty; when set, the topic is "
        "ignored",
    ),
    ParameterSpec(
        "foot_links",
        None,
        ParameterType.PARAMETER_STRING_ARRAY,
        "Foot link per leg as LEG=link (e.g. FR=toe_fr); empty = each leg's leaf link FR..., "
        "FL..., RR..., RL... with three movable joints above it, or of several such leaves the "
        f"one named <leg>_<{'|'.join(FOOT_NAME_SUFFIXES)}> (case-insensitive)",
    ),
    ParameterSpec(
        "joint_aliases",
        None,
        ParameterType.PARAMETER_STRING_ARRAY,
        "Extra incoming joint names as incoming=urdf_joint_name",
    ),
    ParameterSpec(
        "robot_description_topic",
        "robot_description",
        ParameterType.PARAMETER_STRING,
        "Topic of the robot description (std_msgs/String, transient local, as "
        "robot_state_publisher publishes it) followed when neither robot_description nor "
        "urdf_file is set; empty = none",
        read_only=True,
    ),
)
BASE_FRAME_PARAMETER = ParameterSpec(
    "base_frame",
    "",
    ParameterType.PARAMETER_STRING,
    "frame_id of the feet; empty = the URDF's root link (trunk for the embedded A1, base for "
    "Unitree's)",
)


class RobotSource:
    """The robot of ``node``: declares the model parameters, follows the description topic, and
    calls ``on_change(config)`` whenever another robot is accepted (never for the first one,
    :attr:`config`, which the node reads once it is constructed).

    Raises :class:`LegFkError` when the robot the node starts with cannot be used.
    """

    def __init__(
        self, node: Node, on_change: Callable[[RobotConfig], None], inputs: GuardedInputs
    ) -> None:
        """``inputs``: the node's guarded subscriptions, which the topic joins."""
        self._node = node
        self._on_change = on_change
        for spec in PARAMETERS:
            spec.declare(node)
        self._topic_text = ""  # the latest description from the topic that was not rejected
        self._last_received = ""
        self._pending: RobotConfig | None = None
        self._ignored_logged = False
        topic = str(parameter_value(node, "robot_description_topic"))
        self.topic_name = _resolved_topic(node, topic) if topic else ""
        self.topic_status = (
            "not followed (robot_description_topic is empty)" if not topic else "nothing received"
        )
        self.topic_rejected = False  # the latest description from the topic was refused
        self.config = self._build(self._values({}))
        node.add_on_set_parameters_callback(self._check_parameters)
        node.add_post_set_parameters_callback(self._apply_parameters)
        if topic:
            inputs.subscribe(
                String, topic, message_reader(String), self._on_description, DESCRIPTION_QOS
            )
        node.get_logger().info(self._precedence())

    def _precedence(self) -> str:
        explicit = self._explicit(self._values({}))
        if not self.topic_name:
            return f"robot: {self.config.source} (no robot_description topic followed)"
        if explicit:
            return (
                f"robot: {self.config.source}; parameter {explicit} is set, so "
                f"{self.topic_name} is ignored"
            )
        return (
            f"robot: {self.config.source} until a description arrives on {self.topic_name} "
            "(followed)"
        )

    # --- parameters ------------------------------------------------------------------------

    def _values(self, changes: dict[str, object]) -> dict[str, object]:
        return parameter_values(self._node, MODEL_PARAMETERS, changes)

    def base_frame(self, changes: Mapping[str, object]) -> str:
        """The frame of the feet and targets: the node's ``base_frame`` parameter
        (:data:`BASE_FRAME_PARAMETER`, with ``changes`` over the stored value), or when it is
        empty the root link of the current robot.
        """
        value = parameter_values(self._node, (BASE_FRAME_PARAMETER.name,), changes)
        return str(value[BASE_FRAME_PARAMETER.name]) or self.config.quadruped.base_frame

    @staticmethod
    def _explicit(values: dict[str, object]) -> str:
        """The explicitly set parameter that wins over the topic, or ''."""
        return next((name for name in EXPLICIT_PARAMETERS if values[name]), "")

    def _build(self, values: dict[str, object], topic_text: str | None = None) -> RobotConfig:
        """The robot for these parameter values and a topic description (default: the latest)."""
        topic_text = self._topic_text if topic_text is None else topic_text
        feet, aliases = string_list(values["foot_links"]), string_list(values["joint_aliases"])
        if self._explicit(values) or not topic_text:
            return load_robot(
                str(values["robot_description"]), str(values["urdf_file"]), feet, aliases
            )
        return load_robot(topic_text, "", feet, aliases, description_name=self.topic_name)

    def _check_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        changes = {p.name: p.value for p in parameters if p.name in MODEL_PARAMETERS}
        self._pending = None
        if not changes:
            return SetParametersResult(successful=True)
        try:
            # Applied by _apply_parameters, once rclpy has stored the values. The size cap is
            # checked before any parsing (urdf.checked_urdf_text).
            self._pending = self._build(self._values(changes))
        except LegFkError as error:
            self._node.get_logger().warn(
                f"parameter change rejected, keeping {self.config.source}: {error}"
            )
            return SetParametersResult(successful=False, reason=str(error))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, _parameters: list[Parameter]) -> None:
        if self._pending is not None:
            config, self._pending = self._pending, None
            self._accept(config)

    # --- the topic -------------------------------------------------------------------------

    def _on_description(self, msg: String) -> None:
        text = msg.data
        if text == self._last_received:
            return  # republished unchanged: no reload
        self._last_received = text
        explicit = self._explicit(self._values({}))
        if explicit:
            self._topic_text = text
            self.topic_status = f"ignored: parameter {explicit} is set"
            if not self._ignored_logged:
                self._ignored_logged = True
                self._node.get_logger().info(
                    f"ignoring the description on {self.topic_name}: parameter {explicit} is set "
                    "and wins"
                )
            return
        try:
            config = self._build(self._values({}), text)
        except LegFkError as error:
            self.topic_rejected = True
            self.topic_status = f"rejected: {error}"
            self._node.get_logger().warn(
                f"description on {self.topic_name} rejected, keeping {self.config.source}: {error}"
            )
            return
        self._topic_text = text
        self.topic_rejected = False
        self.topic_status = "accepted"
        self._accept(config)

    def _accept(self, config: RobotConfig) -> None:
        self.config = config
        self._node.get_logger().info(
            f"loaded {config.source}: root link '{config.quadruped.base_frame}', feet "
            f"{[leg.chain.foot_link for leg in config.quadruped.legs]}"
        )
        self._on_change(config)


def _resolved_topic(node: Node, topic: str) -> str:
    """The full name of ``topic`` for ``node``; :class:`LegFkError` names the parameter if
    invalid.
    """
    try:
        return node.resolve_topic_name(topic)
    except Exception as error:  # rclpy raises its internal RCLError for a bad name
        raise LegFkError(
            f"robot_description_topic '{topic}' is not a valid topic name: {error}"
        ) from error
