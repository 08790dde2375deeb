"""``a1-leg-fk verify``: call the node's verify_fk (std_srvs/Trigger) and print its answer.

:func:`call_verify` is shared with ``a1-leg-fk demo``.
"""

from __future__ import annotations

import argparse
import sys
import threading
import time
from collections.abc import Sequence

from a1_leg_fk.cli.common import (
    EXIT_FAILED,
    EXIT_INTERRUPTED,
    EXIT_NO_ANSWER,
    EXIT_OK,
    Ros,
    namespace_parent,
    positive,
    prefixed,
    with_ros,
)


def add_parser(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Register ``verify`` with the ``a1-leg-fk`` sub-commands."""
    verify = commands.add_parser(
        "verify",
        parents=[namespace_parent()],
        help="call verify_fk: compare the node's feet with PyBullet's for the last joint state",
        description="Call the node's verify_fk service (std_srvs/Trigger) and print its answer. "
        "Exit 0 when the node's FK agrees with PyBullet's, 1 when it does not or the node has "
        "no joint state yet, 2 when no service answers within --timeout.",
    )
    verify.add_argument(
        "--timeout",
        type=positive,
        default=5.0,
        metavar="S",
        help="seconds to wait for the service (default 5)",
    )
    verify.set_defaults(handler=run)


VERIFY_ASK_AGAIN_S = 1.0


def call_verify(
    ros: Ros, namespace: str, timeout_s: float, stop: threading.Event
) -> tuple[int, str]:
    """Call verify_fk: ``(exit code, text to print)``."""
    from rclpy.qos import QoSProfile
    from std_srvs.srv import Trigger

    # Every client of a service receives the replies to all its clients: a deeper history keeps
    # ours from being pushed out while others call too.
    client = ros.node.create_client(
        Trigger, prefixed(namespace, "verify_fk"), qos_profile=QoSProfile(depth=100)
    )
    name = ros.node.resolve_service_name(client.srv_name)
    try:
        deadline = time.monotonic() + timeout_s
        while not client.service_is_ready():
            if stop.is_set():
                return EXIT_INTERRUPTED, "verify_fk: interrupted"
            if time.monotonic() > deadline:
                return EXIT_NO_ANSWER, (
                    f"verify_fk: no service {name} within {timeout_s:g} s "
                    "(is foot_fk_node running, in this namespace and ROS domain?)"
                )
            ros.executor.spin_once(timeout_sec=0.05)
        future, asked = client.call_async(Trigger.Request()), time.monotonic()
        deadline = asked + timeout_s
        while not future.done():
            if stop.is_set():
                return EXIT_INTERRUPTED, "verify_fk: interrupted"
            now = time.monotonic()
            if now > deadline:
                return EXIT_NO_ANSWER, f"verify_fk: {name} did not answer within {timeout_s:g} s"
            if now - asked > VERIFY_ASK_AGAIN_S:
                # Fast DDS drops a response sent before the server has matched our reply reader
                # ("failed to send response"); verify_fk only reads, so asking again is safe.
                client.remove_pending_request(future)
                future, asked = client.call_async(Trigger.Request()), now
            ros.executor.spin_once(timeout_sec=0.05)
        response = future.result()
    finally:
        ros.node.destroy_client(client)
    verdict = "OK, the node's FK agrees with PyBullet" if response.success else "FAILED"
    return (
        EXIT_OK if response.success else EXIT_FAILED
    ), f"verify_fk ({name}): {verdict}\n  {response.message}"


def run(options: argparse.Namespace, argv: Sequence[str]) -> int:
    """``a1-leg-fk verify``; ``argv``: the whole command line, for ``rclpy.init``."""
    result = with_ros(
        "verify",
        argv,
        lambda ros, stop: call_verify(ros, options.namespace, options.timeout, stop),
    )
    if result is None:
        return EXIT_NO_ANSWER
    code, text = result
    print(text, file=sys.stdout if code in (EXIT_OK, EXIT_FAILED) else sys.stderr)
    return code
