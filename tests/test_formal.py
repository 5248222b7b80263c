"""The short version of make formal: the stream properties of one small unit proven by
SymbiYosys, their covers reached, and every one-row mutant caught by the property it breaks
(so the checks can fail). The whole, on every unit and pipeline: make formal."""
import shutil

import pytest

from sim.formal import MUTANT_TARGETS, MUTANTS, caught, run, tools_env

UNIT = "texel_decode"
pytestmark = pytest.mark.skipif(shutil.which("yowasp-sby", path=tools_env()["PATH"]) is None,
                                reason="yowasp-sby is not installed")


def test_properties_hold_and_covers_are_reached():
    bmc = run(UNIT, UNIT, {}, "bmc")
    assert bmc["status"] == "pass" and not bmc["failed"], bmc
    cover = run(UNIT, UNIT, {}, "cover")
    assert cover["status"] == "pass" and not cover["failed"], cover


@pytest.mark.parametrize("mutant", MUTANT_TARGETS[UNIT])
def test_mutant_is_caught(mutant):
    r = run(UNIT, UNIT, {}, "bmc", mutant)
    assert caught(r), (f"{mutant} ({MUTANTS[mutant][0]}) should fail "
                       f"{MUTANTS[mutant][1]}: {r}")
