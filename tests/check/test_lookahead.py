"""A run that read the future says so: a clairvoyant flag edited in meta.json fails ``clairvoyant``.

The flag is no input of the digest, so nothing else would catch it; the strategy class under the run's recorded
options says whether the run read the future (hindsight always, FL when it counts the day's own orders).
"""

from __future__ import annotations

import pytest

from check.tamper import assert_passes, copy, edit_meta, violations


@pytest.fixture
def seer_copy(seers, tmp_path):
    return copy(seers, tmp_path)


@pytest.mark.parametrize("run", ["hindsight", "fl"])
@pytest.mark.parametrize("flag", [False, None])
def test_a_clairvoyant_run_recorded_online_fails(seer_copy, run, flag):
    def edit(meta):
        if flag is None:
            meta["runs"][run].pop("clairvoyant")
        else:
            meta["runs"][run]["clairvoyant"] = flag

    edit_meta(seer_copy, edit)
    found = violations(seer_copy)
    assert set(found) <= {"clairvoyant", "report"}, found  # the flag is no input: only the label it gives differs
    (message,) = found["clairvoyant"]
    assert message.startswith(f"{run}: meta.json records the run as online") and "reads the future" in message


def test_a_flag_that_is_not_true_or_false_fails(seer_copy):
    edit_meta(seer_copy, lambda m: m["runs"]["hindsight"].update(clairvoyant="yes"))
    assert "records clairvoyant 'yes'" in violations(seer_copy)["clairvoyant"][0]


def test_an_online_run_marked_clairvoyant_passes(seer_copy):
    """Marking an online run clairvoyant only ranks it apart: nothing it shows is false."""
    edit_meta(seer_copy, lambda m: m["runs"]["mb"].update(clairvoyant=True))
    assert_passes(seer_copy)
