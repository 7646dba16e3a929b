"""The number fields' rules, without a browser: which line an Enter enters, and the stepper's
series (:mod:`mechviz.viz.scene.fields`)."""

from __future__ import annotations

import pytest

from mechviz.viz.scene.fields import entered_line, stepped


@pytest.mark.parametrize(
    ("before", "after", "expected"),
    [
        ("2.5", "2.5\n", (True, "2.5")),  # Enter at the end
        ("2.5", "2.\n5", (True, "2.5")),  # Enter inside the number enters the whole line
        ("2.5\n", "2.5\n0.4\n", (True, "0.4")),  # several keys in one message, then Enter
        ("0.2", "0.2\n", (True, "0.2")),
        ("", "1e-2\n", (True, "1e-2")),  # pasted with its newline
        ("2.5\n0.4", "2.5\n0.4\n", (True, "0.4")),  # the next number, on the new line
        ("2.", "2.5", (False, None)),  # still typing
        ("2.5\n", "0", (False, None)),  # all selected and typed over
        ("2.5", "2\n.\n5", (True, None)),  # several Enters at once: which line is not known
    ],
)
def test_the_number_entered_is_the_line_enter_was_pressed_on(before, after, expected):
    assert entered_line(before, after) == expected


@pytest.mark.parametrize(
    ("x", "lo", "hi", "up", "down"),
    [
        (0.025, None, None, 0.05, 0.02),
        (1.0, 0.001, 1000.0, 2.0, 0.5),
        (0.5, None, None, 1.0, 0.2),
        (7.3, None, None, 10.0, 5.0),
        (-0.3, -1.0, 1.0, -0.2, -0.5),  # negative values mirrored: up is towards 0
        (1000.0, 0.001, 1000.0, 1000.0, 500.0),  # held to the range
        (0.0, -1.0, 1.0, 0.001, -0.001),
    ],
)
def test_a_stepper_goes_to_the_neighbouring_value_of_the_1_2_5_series(x, lo, hi, up, down):
    assert stepped(x, 1, lo, hi) == up
    assert stepped(x, -1, lo, hi) == down
