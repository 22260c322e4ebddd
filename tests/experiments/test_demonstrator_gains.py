"""The demonstrator-gain experiment runs real episodes and reports what happened."""

from __future__ import annotations

from impact_experiments.demonstrator_gains import main


def test_shipped_gains_carry_a_2kg_hammer_near_the_nominal_height(capsys):
    main(["--kp", "1", "--ki", "2", "--masses", "2", "--episodes", "1", "--seed", "123"])
    line = capsys.readouterr().out.strip()
    assert "m=2 kg: 1/1" in line
    low, high = (float(x) for x in line.split("height ")[1].removesuffix(" cm").split(" to "))
    assert -4.0 < low < 0.0 < high < 4.0  # sag removed, no limit cycle (k_p = 4 at 8 kg: 16 cm)
