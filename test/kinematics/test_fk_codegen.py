"""The generated FK source: a golden copy of the A1's, tidy text on every robot, and tracebacks
that show the generated lines (linecache)."""

from __future__ import annotations

import gc
import linecache
import re
import traceback
from pathlib import Path

import pybullet_data
import pytest
from exported_urdf import exported_quadruped

from a1_leg_fk.kinematics.compiled_leg import CompiledLeg
from a1_leg_fk.kinematics.quadruped import Quadruped

GOLDEN = Path(__file__).parent / "golden" / "a1_FR_fk_source.txt"
DATA = Path(pybullet_data.getDataPath())
ROBOTS = {
    "a1": Quadruped.from_urdf,
    "aliengo": lambda: Quadruped.from_urdf(str(DATA / "aliengo" / "aliengo.urdf")),
    "mini_cheetah": lambda: Quadruped.from_urdf(
        str(DATA / "mini_cheetah" / "mini_cheetah.urdf"),
        {"FR": "toe_fr", "FL": "toe_fl", "RR": "toe_hr", "RL": "toe_hl"},
    ),
    "b2_like": lambda: Quadruped.from_urdf(exported_quadruped("b2")),
}
ALIAS_LINE = re.compile(r"^\s+\w+ = \w+$", re.MULTILINE)


def test_the_a1_front_right_source_is_the_golden_one() -> None:
    """Regenerate with: Quadruped.from_urdf().legs[0].source (review the diff before
    committing)."""
    assert Quadruped.from_urdf().legs[0].source == GOLDEN.read_text(encoding="utf-8")


@pytest.mark.parametrize("robot", sorted(ROBOTS))
def test_the_generated_text_is_tidy(robot: str) -> None:
    """No double signs (``s1*-p1``, ``-0.2*-s2``, ``a + -b``) and no alias lines (``v5 = v3``)."""
    for leg in ROBOTS[robot]().legs:
        source = leg.source
        for untidy in ("*-", "+ -", "- -", "--"):
            assert untidy not in source, f"{robot} {leg.chain.leg}: {untidy!r} in\n{source}"
        assert not ALIAS_LINE.findall(source), ALIAS_LINE.findall(source)


def test_a_traceback_shows_the_generated_line() -> None:
    leg = Quadruped.from_urdf().legs[0]
    with pytest.raises(TypeError) as error:
        leg.position("not an angle", 0.0, 0.0)
    text = "".join(traceback.format_exception(error.value))
    assert "<a1_leg_fk generated FK of leg FR #" in text
    assert "c0 = _cos(q0)" in text  # the generated line itself, from linecache


def test_the_generated_lines_leave_linecache_with_their_leg() -> None:
    leg = CompiledLeg(Quadruped.from_urdf().legs[1].chain)
    filename = leg.position.__code__.co_filename
    assert linecache.getline(filename, 1).startswith("def position_from_trig(")
    del leg
    gc.collect()
    assert filename not in linecache.cache
