"""Components driven period by period give LinuxCNC's values, recorded with halsampler
from LinuxCNC 2.9 running the same HAL files (see files/README.md)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.hal.halrun_util import FILES, run_cnc


def _rows(text: str) -> list[list[float]]:
    return [[float(word) for word in line.split()] for line in text.splitlines() if line.strip()]


@pytest.mark.parametrize(
    ("hal_file", "samples", "count"),
    [
        # siggen driving limit3, limit2, ddt, lowpass and pid
        ("lcnc_oracle.hal", "lcnc_oracle_samples.txt", 400),
        # bit, timer and counting components, stepgen, sim_encoder and encoder
        ("lcnc_oracle2.hal", "lcnc_oracle2_samples.txt", 1200),
        # limit3 following moving inputs under all its limits
        ("lcnc_oracle_limit3.hal", "lcnc_oracle_limit3_samples.txt", 1500),
        # stepgen in position mode, a fuller pid, logic and arithmetic components
        ("lcnc_oracle3.hal", "lcnc_oracle3_samples.txt", 1600),
        # stepgen step types 0-14 and a user step type, reversing under dirdelay
        ("lcnc_oracle_stepgen.hal", "lcnc_oracle_stepgen_samples.txt", 2400),
        # small components of the sample configs and tests: abs_s32 ... lut5
        ("lcnc_oracle_new1.hal", "lcnc_oracle_new1_samples.txt", 6000),
        # orient, estop_latch, biquad, multiclick, encoder_ratio, mux_generic, counter,
        # modmath, weighted_sum, pwmgen
        ("lcnc_oracle_new2.hal", "lcnc_oracle_new2_samples.txt", 6000),
        # corexy_by_hal, sim_matrix_kb, xhc_hb04_util, thc, sim_parport, sim_axis_hardware,
        # anglejog, carousel (single and counts), eoffset_per_angle
        ("lcnc_oracle_new3.hal", "lcnc_oracle_new3_samples.txt", 6000),
    ],
)
def test_components_match_linuxcnc_period_by_period(
    tmp_path: Path, hal_file: str, samples: str, count: int
) -> None:
    result = run_cnc("halrun", "-f", str(FILES / hal_file), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    ours = _rows(result.stdout)
    theirs = _rows((FILES / samples).read_text())
    assert len(ours) == len(theirs) == count
    for mine, expected in zip(ours, theirs, strict=True):
        for column, (value, reference) in enumerate(zip(mine, expected, strict=True)):
            assert value == pytest.approx(reference, rel=1e-5, abs=2e-6), (
                f"sample {int(mine[0])}, column {column}: {value} != {reference}"
            )
