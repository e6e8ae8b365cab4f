"""treesketch.cli_common: the comma-separated values the commands read."""

from __future__ import annotations

import pytest
import typer

from treesketch.cli_common import comma_list, styles_kept


def test_comma_list_strips_lowers_and_drops_blanks() -> None:
    assert comma_list(" SG, pen,,Felt ", "style") == ("sg", "pen", "felt")


def test_comma_list_of_nothing_names_what_was_wanted() -> None:
    with pytest.raises(typer.BadParameter, match="give at least one view"):
        comma_list(" , ", "view")


def test_styles_kept_none_keeps_every_sketch() -> None:
    assert styles_kept(None) is None
    assert styles_kept("Felt") == ("felt",)
