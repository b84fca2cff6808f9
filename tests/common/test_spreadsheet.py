"""Text cells that a spreadsheet would run as formulas get a leading apostrophe."""

import pytest

from common.spreadsheet import safe_cell


@pytest.mark.parametrize("text", ["=1+1", "+1", "-1+2", "@SUM(A1)", "\tx", "\rx"])
def test_every_formula_start_is_neutralised(text):
    assert safe_cell(text) == "'" + text


def test_numbers_and_plain_text_stay_as_they_are():
    assert (safe_cell(-2.5), safe_cell(3), safe_cell("plain"), safe_cell("")) == (
        -2.5,
        3,
        "plain",
        "",
    )
