"""The one safe document loader (trajkit.io.document) and every file input that uses it.

Hostile documents (alias bombs, deep nesting, duplicate keys, YAML 1.1
booleans, non-UTF-8 bytes, huge files) must be refused with one line naming
the source, by both YAML back ends (libyaml's parser and PyYAML's pure-Python
one), and by every command that reads a file.
"""

from __future__ import annotations

import json
import math

import pytest

from trajkit.cli import main
from trajkit.errors import InvalidInputError
from trajkit.io import document
from trajkit.io.document import LineDict, parse_document, plain, read_document

LOADERS = [document._PyLoader] + ([document._CLoader] if hasattr(document, "_CLoader") else [])

BOMB = (
    'a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]\n'
    "b: &b [*a,*a,*a,*a,*a,*a,*a,*a,*a]\n"
    "c: &c [*b,*b,*b,*b,*b,*b,*b,*b,*b]\n"
    "d: &d [*c,*c,*c,*c,*c,*c,*c,*c,*c]\n"
    "e: &e [*d,*d,*d,*d,*d,*d,*d,*d,*d]\n"
    "f: &f [*e,*e,*e,*e,*e,*e,*e,*e,*e]\n"
    "g: &g [*f,*f,*f,*f,*f,*f,*f,*f,*f]\n"
    "h: &h [*g,*g,*g,*g,*g,*g,*g,*g,*g]\n"
)


def yaml_both(text, **kw):
    """Parse with every YAML back end; they must agree (value or message)."""
    results = []
    for cls in LOADERS:
        try:
            results.append(("ok", document._parse_yaml(text, "doc.yaml", kw.get("max_depth", 64), cls)))
        except InvalidInputError as exc:
            results.append(("error", str(exc)))
    kinds = {r[0] for r in results}
    assert len(kinds) == 1, results
    if results[0][0] == "error":
        raise InvalidInputError(results[0][1])
    assert all(repr(r[1]) == repr(results[0][1]) for r in results)
    return results[0][1]


def test_core_schema_scalars():
    doc = yaml_both("a: yes\nb: 1e3\nc: '1e3'\nd: 0777\ne: 0o17\nf: .inf\ng: ~\nh: 2024-01-01\n"
                    "i: true\nj: -.5\nk: +3\nl: 0x1F\nm: on\nn: NO\no: -.inf\np:\n")
    assert doc == {"a": "yes", "b": 1000.0, "c": "1e3", "d": 777, "e": 15, "f": math.inf,
                   "g": None, "h": "2024-01-01", "i": True, "j": -0.5, "k": 3, "l": 31,
                   "m": "on", "n": "NO", "o": -math.inf, "p": None}
    assert type(doc["b"]) is float and type(doc["d"]) is int and type(doc["i"]) is bool
    assert math.isnan(yaml_both("x: .nan")["x"])


def test_lines_are_recorded():
    doc = yaml_both("a:\n  b: 1\n  c:\n    - 1\n    - {d: x}\n")
    assert isinstance(doc, LineDict)
    assert doc.key_lines == {"a": 1}
    assert doc["a"].key_lines == {"b": 2, "c": 3}
    assert doc["a"]["c"].item_lines == [4, 5]
    assert plain(doc) == {"a": {"b": 1, "c": [1, {"d": "x"}]}}
    assert type(plain(doc)) is dict


@pytest.mark.parametrize("text, match", [
    (BOMB, r"doc\.yaml:1: anchors \(&a\) are not supported"),
    ("a: [1]\nb: *a\n", r"doc\.yaml:2: aliases \(\*a\) are not supported"),
    ("base: &b {x: 1}\nc:\n  <<: *b\n", r"anchors \(&b\) are not supported"),
    ("a: !!python/object/apply:os.system [ls]\n", r"doc\.yaml:1: explicit tags .* are not supported"),
    ("a: !!binary aGVsbG8=\n", r"explicit tags"),
    ("a: !!str 12\n", r"explicit tags"),
    ("a: 1\nb: 2\na: 3\n", r"doc\.yaml:3: duplicate key 'a'"),
    ("{[1, 2]: x}\n", r"a mapping key must be a plain value"),
    ("[" * 100_000 + "]" * 100_000, r"nested deeper than 64 levels|nest"),
    ("a: " + "9" * 5000 + "\n", r"doc\.yaml:1: integer 9+\.\.\. is too long"),
    ("a: [1, 2\nb: 3\n", r"doc\.yaml:\d: not valid YAML: "),
    ("a: 1e999\n", r"doc\.yaml:1: number 1e999 is out of the range of a float"),
])
def test_hostile_yaml_is_refused(text, match):
    with pytest.raises(InvalidInputError, match=match):
        yaml_both(text)


def test_depth_cap_is_exact():
    ok = "[" * 64 + "]" * 64
    assert yaml_both(ok) is not None
    with pytest.raises(InvalidInputError, match="nested deeper than 64 levels"):
        yaml_both("[" * 65 + "]" * 65)
    nested_map = "".join("  " * i + f"k{i}:\n" for i in range(70)) + "  " * 70 + "1\n"
    with pytest.raises(InvalidInputError, match="nested deeper than 64 levels"):
        yaml_both(nested_map)


@pytest.mark.parametrize("kind", ["yaml", "json"])
def test_bytes_size_and_encoding(kind):
    with pytest.raises(InvalidInputError, match=r"in\.doc: not UTF-8 text \(byte 0xff at offset 3\)"):
        parse_document(b"{}\n\xff\xfe", source="in.doc", kind=kind)
    with pytest.raises(InvalidInputError, match=r"in\.doc: larger than 1\.0 KiB \(1\.0 KiB\)"):
        parse_document(b" " * 1025, source="in.doc", kind=kind, max_bytes=1024)
    with pytest.raises(InvalidInputError, match="contains a NUL character"):
        parse_document('{"a": 1}\x00', source="in.doc", kind=kind)
    assert parse_document('\ufeff{"a": 1}'.encode(), kind=kind) == {"a": 1}


@pytest.mark.parametrize("text, match", [
    ('{"a": 1, "a": 2}', r"duplicate key 'a'"),
    ('{"a": NaN}', r"NaN is not valid JSON"),
    ('{"a": -Infinity}', r"-Infinity is not valid JSON"),
    ('{"a": -1e999}', r"number -1e999 is out of the range of a float"),
    ("[" * 100_000 + "]" * 100_000, r"nested deeper than 64 levels"),
    ('{"a": 1,}', r"src:1: not valid JSON: .*column 9"),
    ('{"a": ' + "9" * 5000 + "}", r"not valid JSON"),
])
def test_hostile_json_is_refused(text, match):
    with pytest.raises(InvalidInputError, match=match):
        parse_document(text, source="src", kind="json")


def test_json_depth_ignores_brackets_in_strings():
    doc = {"a": "[[[[{{{{" * 50, "b": [[1, 2], {"c": "]]]\\\"[[["}]}
    assert parse_document(json.dumps(doc), kind="json") == doc


def test_read_document_reads_no_more_than_the_cap(tmp_path):
    big = tmp_path / "big.yaml"
    big.write_bytes(b"a: 1\n" + b"#" * (3 * 1024 * 1024))
    with pytest.raises(InvalidInputError, match=r"big\.yaml: larger than 2\.0 MiB"):
        read_document(big)
    with pytest.raises(InvalidInputError, match="is a folder"):
        read_document(tmp_path)
    with pytest.raises(OSError):
        read_document(tmp_path / "missing.yaml")


# ----------------------------------------------------------------- every command
PROGRAM_OK = ("robot: arm6\npoints:\n  a: {joints_deg: [0, 10, 0, 0, 30, 0]}\n"
              "program:\n  - PTP: a\n")


def _cli(capsys, *argv):
    code = main(list(argv))
    captured = capsys.readouterr()
    return code, captured.err.strip()


@pytest.mark.parametrize("command, name", [
    (("run", "--period", "0.01"), "prog.yaml"),
    (("ptp", "--file"), "job.yaml"),
    (("pallet",), "job.yaml"),
    (("path", "--file"), "path.yaml"),
])
@pytest.mark.parametrize("content, match", [
    (BOMB.encode(), r"anchors \(&a\) are not supported"),
    (b"a: 1\na: 2\n", r":2: duplicate key 'a'"),
    (b"\xff\xfe\x00a", r"not UTF-8 text"),
    (("[" * 100_000 + "]" * 100_000).encode(), r"nest"),
])
def test_every_command_refuses_hostile_files(tmp_path, capsys, command, name, content, match):
    f = tmp_path / name
    f.write_bytes(content)
    code, err = _cli(capsys, *command, str(f))
    assert code == 2
    assert "\n" not in err and "Traceback" not in err
    assert err.startswith(f"trajkit {command[0]}: error: ")
    import re
    assert re.search(match, err), err


@pytest.mark.parametrize("content, match", [
    ("start: [0]\ngoal: [1]\nlimits: {v_max: yes, a_max: 2, j_max: 3}\n",
     r"field limits\.0\.v_max: Input should be a valid number \(got 'yes'\)"),
    ("start: [0]\ngoal: [1]\nlimits: {v_max: '1e3', a_max: 2, j_max: 3}\n",
     r"field limits\.0\.v_max: Input should be a valid number \(got '1e3'\)"),
    ("start: [0]\ngoal: [1]\nlimits: {v_max: true, a_max: 2, j_max: 3}\n",
     r"field limits\.0\.v_max: Input should be a valid number \(got True\)"),
    ("start: ['0']\ngoal: [1]\nlimits: {v_max: 1, a_max: 2, j_max: 3}\n",
     r"field start\.0: Input should be a valid number \(got '0'\)"),
])
def test_strings_and_booleans_are_not_numbers(tmp_path, capsys, content, match):
    f = tmp_path / "job.yaml"
    f.write_text(content)
    code, err = _cli(capsys, "ptp", "--file", str(f), "--json")
    assert code == 2
    import re
    assert re.search(match, err), err


def test_no_limit_is_spelled_inf(tmp_path, capsys):
    f = tmp_path / "job.yaml"
    f.write_text("start: [0]\ngoal: [1]\nlimits: {v_max: .inf, a_max: 2, j_max: 'inf'}\n")
    code, _ = _cli(capsys, "ptp", "--file", str(f))
    assert code == 0


def test_program_numbers_are_strict(tmp_path, capsys):
    f = tmp_path / "prog.yaml"
    f.write_text(PROGRAM_OK.replace("[0, 10, 0, 0, 30, 0]", "[0, yes, 0, 0, 30, 0]"))
    code, err = _cli(capsys, "run", "--period", "0.01", str(f))
    assert code == 2 and "prog.yaml:3: points.a.joints_deg[1]: Input should be a valid number (got 'yes')" in err
    f.write_text(PROGRAM_OK)
    assert _cli(capsys, "run", "--period", "0.01", str(f))[0] == 0
    f.write_text(PROGRAM_OK + "  - WAIT: {time_s: '1'}\n")
    code, err = _cli(capsys, "run", "--period", "0.01", str(f))
    assert code == 2 and "time_s: Input should be a valid number (got '1')" in err
