"""The ``.solu`` known-values file: every tag read, every malformed line one error naming the file and line,
written sorted and byte for byte the same, names checked against the instances."""

from __future__ import annotations

from pathlib import Path

import pytest

from rpbench.exceptions import ParameterError
from rpbench.results.solu import Known, check_names, read_solu, write_solu

GOOD = """\
# known values of a test set
   # an indented comment

=opt=   toy_mb_round00025  1754455
=best=  big-pairing        779409.5
=bound= huge               -12e3
=inf=   broken
=unkn=  open_question
"""


def test_every_tag_is_read(tmp_path):
    path = tmp_path / "set.solu"
    path.write_text(GOOD)
    assert read_solu(path) == {
        "toy_mb_round00025": Known("opt", 1754455.0),
        "big-pairing": Known("best", 779409.5),
        "huge": Known("bound", -12000.0),
        "broken": Known("inf", None),
        "open_question": Known("unkn", None),
    }


def test_written_sorted_with_the_header_and_read_back(tmp_path):
    entries = {"b": Known("opt", 12.0), "a": Known("best", 2.5), "c": Known("inf"), "d": Known("bound", -3.0)}
    one, two = tmp_path / "one.solu", tmp_path / "two.solu"
    write_solu(one, entries, ["rpbench library S", "", "# already a comment"])
    write_solu(two, dict(reversed(entries.items())), ["rpbench library S", "", "# already a comment"])
    assert one.read_bytes() == two.read_bytes()  # insertion order does not matter
    assert one.read_text().splitlines() == [
        "# rpbench library S",
        "#",
        "# already a comment",
        "=best= a 2.5",
        "=opt= b 12",  # a whole number without ".0"
        "=inf= c",
        "=bound= d -3",
    ]
    assert read_solu(one) == entries
    assert not list(tmp_path.glob(".*partial*"))  # no temporary file left


def test_a_value_that_is_no_whole_number_round_trips_exactly(tmp_path):
    value = 0.1 + 0.2  # 0.30000000000000004
    write_solu(tmp_path / "x.solu", {"m": Known("opt", value)}, [])
    assert read_solu(tmp_path / "x.solu")["m"].value == value


@pytest.mark.parametrize(
    "line, match",
    [
        ("=foo= m 1", "unknown tag '=foo='"),
        ("== m 1", "unknown tag '=='"),
        ("opt m 1", "is not a known-value line"),
        ("m 1", "is not a known-value line"),
        ("=opt= m", "has 2 fields; expected =opt= NAME VALUE"),
        ("=best=", "has 1 fields; expected =best= NAME VALUE"),
        ("=opt= m 1 2", "has 4 fields; expected =opt= NAME VALUE"),
        ("=inf= m 3", "has 3 fields; expected =inf= NAME"),
        ("=unkn= m x", "has 3 fields; expected =unkn= NAME"),
        ("=opt= m abc", "value 'abc' of 'm' is not a finite decimal number"),
        ("=bound= m nan", "value 'nan' of 'm' is not a finite decimal number"),
        ("=best= m inf", "value 'inf' of 'm' is not a finite decimal number"),
        ("=opt= m 1e999", "value '1e999' of 'm' is not a finite decimal number"),
        ("=opt= m 1_000", "value '1_000' of 'm' is not a finite decimal number"),
        ("=opt= m 0x10", "value '0x10' of 'm' is not a finite decimal number"),
        ("=opt= m 5  # trailing", "has 5 fields"),
    ],
)
def test_each_malformed_line_is_one_error_naming_file_and_line(tmp_path, line, match):
    path = tmp_path / "bad.solu"
    path.write_text(f"# header\n=opt= fine 1\n\n{line}\n=opt= after 2\n")
    with pytest.raises(ParameterError) as err:
        read_solu(path)
    message = str(err.value)
    assert "\n" not in message and message.startswith(f"{path}, line 4: ")
    assert match in message


def test_a_name_given_twice_names_both_lines(tmp_path):
    path = tmp_path / "twice.solu"
    path.write_text("=opt= m 1\n# x\n=best= m 1\n")
    with pytest.raises(ParameterError, match=r"line 3: instance 'm' is given again \(first on line 1\)"):
        read_solu(path)


def test_unreadable_files(tmp_path):
    with pytest.raises(ParameterError, match="cannot read known values file"):
        read_solu(tmp_path / "missing.solu")
    (tmp_path / "latin1.solu").write_bytes(b"=opt= caf\xe9 1\n")
    with pytest.raises(ParameterError, match="is not UTF-8 text"):
        read_solu(tmp_path / "latin1.solu")


def test_known_checks_its_value():
    with pytest.raises(ParameterError, match="needs a value"):
        Known("opt", None)
    with pytest.raises(ParameterError, match="takes no value"):
        Known("inf", 3.0)
    with pytest.raises(ParameterError, match="not one of"):
        Known("optimal", 3.0)
    with pytest.raises(ParameterError, match="not a finite number"):
        Known("bound", float("nan"))


def test_names_that_cannot_be_written(tmp_path):
    with pytest.raises(ParameterError, match="cannot be written"):
        write_solu(tmp_path / "x.solu", {"two words": Known("inf")}, [])
    assert not (tmp_path / "x.solu").exists()


def test_check_names():
    known = {"a": Known("opt", 1.0), "b": Known("inf")}
    check_names(known, ["a", "b", "c"], "set.solu")  # every name names an instance: fine
    with pytest.raises(ParameterError) as err:
        check_names(known, ["a", "c"], "set.solu")
    assert str(err.value).startswith("set.solu: 'b' names no instance benchmarked here (2 instances)")
    with pytest.raises(ParameterError, match="'a', 'b' name no instance"):
        check_names(known, [], "set.solu")


def test_check_names_skips_library_instances_not_benchmarked():
    known = {"a": Known("opt", 1.0), "lib": Known("opt", 2.0), "typo": Known("inf")}
    assert check_names(known, ["a"], "set.solu", library=["lib", "typo"]) == ["lib", "typo"]
    with pytest.raises(ParameterError, match="'typo' names no instance benchmarked here .* or of the library"):
        check_names(known, ["a"], "set.solu", library=["lib"])


def test_a_library_wide_solu_judges_a_subset(tmp_path, capsys):
    """The committed S tier benched against the whole library's file: its lines judge, the others are skipped."""
    from rpbench.cli import main

    repo = Path(__file__).resolve().parents[2]
    one = sorted((repo / "instances" / "library" / "S").glob("toy_*_mb_*.npz"))[0]
    rc = main(
        [
            "bench",
            str(one),
            "--solu",
            str(repo / "instances" / "rpbench.solu"),
            "--solver",
            "matching",
            "--no-isolate",
            "--no-progress",
            "--repeat",
            "1",
        ]
    )
    out, err = capsys.readouterr()
    assert rc == 0 and "name library instances not benchmarked here" in err
    assert "optimal" in out.splitlines()[2]
