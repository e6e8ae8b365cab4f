"""benchmarks/lib/results_md.py: a benchmark's --write replaces its own section of RESULTS.md."""

from __future__ import annotations

from benchmarks.lib.results_md import write_section

RESULTS = """# Benchmark results

## Where we stand

| question | figure |

## Generator

### Generator: grow + mesh

old table

#### a note inside it

old note

### Generator limits

limits table

## Service

service text
"""


def test_a_section_under_a_subject_is_replaced_at_its_own_level(tmp_path) -> None:
    path = tmp_path / "RESULTS.md"
    path.write_text(RESULTS)
    write_section("## Generator: grow + mesh\n\nnew table\n\n### a new note\n\nnew note\n", path)
    text = path.read_text()
    assert "old table" not in text and "old note" not in text
    assert "### Generator: grow + mesh\n\nnew table\n\n#### a new note\n\nnew note\n" in text
    # the sections after it, under the same subject and the next, are kept as they were
    assert "\n### Generator limits\n\nlimits table\n\n## Service\n\nservice text\n" in text
    assert text.startswith("# Benchmark results\n\n## Where we stand\n")


def test_a_new_section_is_appended_and_a_top_level_one_replaced(tmp_path) -> None:
    path = tmp_path / "RESULTS.md"
    path.write_text(RESULTS)
    write_section("## Level of detail\n\nlod table\n", path)
    assert path.read_text().endswith("service text\n\n## Level of detail\n\nlod table\n")
    write_section("## Service\n\nnew service text\n", path)
    text = path.read_text()
    assert "new service text" in text and "\nservice text" not in text
    assert text.endswith("## Service\n\nnew service text\n\n## Level of detail\n\nlod table\n")
