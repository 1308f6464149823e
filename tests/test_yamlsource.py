"""Reading YAML safely with every error located at FILE:LINE:COL."""

from __future__ import annotations

import math
import pickle
import re
import time
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from preform.yamlsource import (
    Document,
    SourceError,
    YamlPath,
    YamlSourceError,
    format_path,
    load_yaml,
    load_yaml_text,
)


def errors_of(text: str, **limits: int) -> list[SourceError]:
    with pytest.raises(YamlSourceError) as caught:
        load_yaml_text(text, "f.yaml", **limits)
    return caught.value.errors


def where(errors: list[SourceError]) -> list[tuple[int, int, str]]:
    return [(e.line, e.column, e.path) for e in errors]


def one(text: str) -> Document:
    (document,) = load_yaml_text(text, "f.yaml")
    return document


# Each case: text, then (line, column, path) and a fragment of the message of its only error.
BROKEN = {
    "duplicate key": (
        "name: a\nweave:\n  warp: 1\n  weft: 2\n  warp: 3\n",
        (5, 3, "weave.warp"),
        "duplicate key 'warp' (first at line 3)",
    ),
    "python object tag": (
        "name: a\nhook: !!python/object/apply:os.system ['ls']\n",
        (2, 7, "hook"),
        "tag !!python/object/apply:os.system is not allowed: it would construct a Python object",
    ),
    "local tag": ("a:\n  - !fabric {x: 1}\n", (2, 5, "a[0]"), "tag !fabric is not allowed"),
    "binary is not plain data": ("a: !!binary aGk=\n", (1, 4, "a"), "tag !!binary"),
    "set is not plain data": ("a: !!set {x, y}\n", (1, 4, "a"), "tag !!set"),
    "str tag on a mapping": ("a: !!str {x: 1}\n", (1, 4, "a"), "does not fit a mapping"),
    "nan": ("a:\n  b: .nan\n", (2, 6, "a.b"), "non-finite number '.nan' is not allowed"),
    "inf": ("a: [1, .inf]\n", (1, 8, "a[1]"), "non-finite number '.inf'"),
    "minus inf": ("a: -.Inf\n", (1, 4, "a"), "non-finite number '-.Inf'"),
    "float overflow": ("a: 1.0e+999\n", (1, 4, "a"), "non-finite number '1.0e+999'"),
    "explicit float nan": ("a: !!float nan\n", (1, 4, "a"), "non-finite number 'nan'"),
    "bad explicit int": ("a: !!int twelve\n", (1, 4, "a"), "'twelve' is not an integer"),
    "bad explicit bool": ("a: !!bool maybe\n", (1, 4, "a"), "'maybe' is not a boolean"),
    "integer key": ("a:\n  1: x\n", (2, 3, "a.1"), "key '1' is read as an integer"),
    "boolean key": ("on: x\n", (1, 1, "on"), "YAML 1.1 reads yes/no/on/off as booleans"),
    "null key": ("~: x\n", (1, 1, "~"), "read as null; keys must be strings, so quote it"),
    "empty key": ("a:\n  ?\n  : x\n", (2, 4, "a"), "mapping key is empty"),
    "list key": ("[1, 2]: x\n", (1, 1, ""), "mapping keys must be strings, not a list"),
    "mapping value indented": ("a: 1\n b: 2\n", (2, 3, ""), "mapping values are not allowed"),
    "tab indentation": ("a:\n\t- 1\n", (2, 1, ""), "use spaces"),
    "unclosed flow list": (
        "a: [1, 2\nb: 3\n",
        (2, 2, ""),
        "expected ',' or ']', but got ':' (while parsing a flow sequence at line 1, column 4)",
    ),
    "unclosed quote": ("a: 'x\n", (2, 1, ""), "found unexpected end of stream"),
    "stray bracket": ("name: x\nweave: {a: 1}}\n", (2, 14, ""), "found '}'"),
    "undefined alias": ("a: 1\nb: *base\n", (2, 4, "b"), "alias *base has no anchor &base"),
    "recursive alias": ("a: &a [1, *a]\n", (1, 11, "a[1]"), "inside the node it refers to"),
    "anchor twice": (
        "a: &x 1\nb: &x 2\n",
        (2, 4, "b"),
        "anchor &x is defined twice (first at line 1)",
    ),
    "merge of a scalar": ("a:\n  <<: 1\n", (2, 7, "a"), "merge key '<<' takes a mapping"),
    "merge of a list holding a scalar": (
        "a: &a {x: 1}\nb:\n  <<: [*a, 2]\n",
        (3, 12, "b"),
        "merge key '<<' takes a mapping or a list of mappings",
    ),
    "merge twice": ("a: &a {x: 1}\nb:\n  <<: *a\n  <<: *a\n", (4, 3, "b.<<"), "duplicate key '<<'"),
    "control character": ("a: x\x07y\n", (1, 5, ""), "character U+0007 is not allowed"),
}


@pytest.mark.parametrize("case", BROKEN.values(), ids=BROKEN.keys())
def test_each_error_is_located_exactly(case: tuple[str, tuple[int, int, str], str]) -> None:
    text, expected_where, fragment = case
    errors = errors_of(text)
    assert where(errors) == [expected_where]
    assert fragment in errors[0].message
    assert errors[0].file == "f.yaml"


def test_every_error_of_a_file_is_reported_in_file_order() -> None:
    text = (
        "name: twill\n"  # 1
        "areal_density_g_m2: .nan\n"  # 2
        "weave:\n"  # 3
        "  warp: 1\n"  # 4
        "  warp: 2\n"  # 5
        "  hook: !!python/name:os.system ''\n"  # 6
        "yes: 3\n"  # 7
        "name: again\n"  # 8
    )
    assert where(errors_of(text)) == [
        (2, 21, "areal_density_g_m2"),
        (5, 3, "weave.warp"),
        (6, 9, "weave.hook"),
        (7, 1, "yes"),
        (8, 1, "name"),
    ]


def test_errors_before_a_syntax_error_are_reported_with_it() -> None:
    errors = errors_of("a: 1\na: 2\nb: -.inf\nc: [1,\n")
    assert where(errors) == [(2, 1, "a"), (3, 4, "b"), (5, 1, "")]
    assert errors[2].message.startswith("syntax error: ")


def test_errors_in_later_documents_carry_their_own_lines() -> None:
    errors = errors_of("x: [a, b]\n---\ny: .inf\n---\nz: 1\nz: 2\n")
    assert where(errors) == [(3, 4, "y"), (6, 1, "z")]


def test_source_error_text() -> None:
    assert (
        str(SourceError("lib.yaml", 3, 7, "weave.warp", "bad")) == "lib.yaml:3:7: weave.warp: bad"
    )
    assert str(SourceError("lib.yaml", 3, 7, "", "bad")) == "lib.yaml:3:7: bad"
    error = YamlSourceError([SourceError("a", 1, 2, "", "x"), SourceError("a", 3, 4, "p", "y")])
    assert str(error) == "a:1:2: x\na:3:4: p: y"


def test_yaml_source_error_survives_pickling() -> None:
    # Errors cross process-pool boundaries in the pipeline.
    error = YamlSourceError([SourceError("a", 1, 2, "p", "x")])
    copy = pickle.loads(pickle.dumps(error))
    assert copy.errors == error.errors
    assert str(copy) == str(error)


def test_format_path() -> None:
    assert format_path(("fabrics", 0, "tows", 12, "width_mm")) == "fabrics[0].tows[12].width_mm"
    assert format_path((3, "a")) == "[3].a"
    assert format_path(()) == ""


NESTED = """\
name: twill 2/2
weave:
  matrix:
    - [1, 0]
    - [0, 1]
tows:
  - kind: warp
    width_mm: 2.5
  -   kind: weft
      width_mm: 3.0
"""


def test_locate_finds_keys_and_items_in_nested_data() -> None:
    document = one(NESTED)
    assert document.data["weave"]["matrix"] == [[1, 0], [0, 1]]
    assert document.locate(()) == (1, 1)
    assert document.locate(("name",)) == (1, 1)
    assert document.locate(("weave",)) == (2, 1)
    assert document.locate(("weave", "matrix")) == (3, 3)
    assert document.locate(("weave", "matrix", 1)) == (5, 7)
    assert document.locate(("weave", "matrix", 1, 1)) == (5, 11)
    assert document.locate(("tows", 1)) == (9, 7)
    assert document.locate(("tows", 1, "width_mm")) == (10, 7)
    assert document.locate_value(("tows", 1, "width_mm")) == (10, 17)
    assert document.locate_value(("name",)) == (1, 7)


def test_locate_falls_back_to_the_closest_existing_ancestor() -> None:
    document = one(NESTED)
    assert document.locate(("tows", 1, "areal_density_g_m2")) == (9, 7)
    assert document.locate(("tows", 7, "kind")) == (6, 1)
    assert document.locate(("missing", "deeper")) == (1, 1)
    # A list index is an int: a string "0" or a boolean does not find item 0 or 1.
    assert document.locate(("tows", "0")) == (6, 1)
    assert document.locate(("tows", True)) == (6, 1)
    # A scalar has no children.
    assert document.locate(("name", "x")) == (1, 1)


def test_document_error_is_located_and_names_the_path() -> None:
    document = one(NESTED)
    error = document.error(("tows", 0, "width_mm"), "must be positive")
    assert str(error) == "f.yaml:8:5: tows[0].width_mm: must be positive"
    error = document.error(("tows", 0, "width_mm"), "must be positive", at_value=True)
    assert (error.line, error.column) == (8, 15)


def test_locate_through_aliases_points_into_the_anchored_mapping() -> None:
    document = one("base: &b\n  tex: 600\nfabric: *b\nlist: [*b]\n")
    assert document.data == {"base": {"tex": 600}, "fabric": {"tex": 600}, "list": [{"tex": 600}]}
    assert document.locate(("fabric",)) == (3, 1)
    assert document.locate_value(("fabric",)) == (3, 9)
    assert document.locate(("fabric", "tex")) == (2, 3)
    assert document.locate(("list", 0)) == (4, 8)
    assert document.locate(("list", 0, "tex")) == (2, 3)


def test_aliased_values_are_independent_copies() -> None:
    document = one("a: &a {x: [1]}\nb: *a\n")
    document.data["b"]["x"].append(2)
    assert document.data["a"] == {"x": [1]}


def test_an_error_inside_an_anchor_is_reported_once_at_the_anchor() -> None:
    errors = errors_of("a: &a {x: .nan}\nb: *a\nc: [*a, *a]\n")
    assert where(errors) == [(1, 11, "a.x")]


def test_merge_keys_explicit_keys_win_then_the_first_source() -> None:
    text = (
        "carbon: &carbon {fibre: carbon, tex: 800, sizing: epoxy}\n"  # 1
        "glass: &glass {fibre: glass, tex: 600, twist: 0}\n"  # 2
        "tow:\n"  # 3
        "  <<: [*carbon, *glass]\n"  # 4
        "  tex: 400\n"  # 5
    )
    document = one(text)
    assert document.data["tow"] == {"tex": 400, "fibre": "carbon", "sizing": "epoxy", "twist": 0}
    assert document.locate(("tow", "tex")) == (5, 3)
    assert document.locate(("tow", "fibre")) == (1, 18)
    assert document.locate(("tow", "twist")) == (2, 40)


def test_merge_of_a_mapping_that_merges_and_of_an_inline_mapping() -> None:
    text = "a: &a {x: 1}\nb: &b {<<: *a, y: 2}\nc: {<<: *b, z: 3}\nd: {<<: {w: 0}}\n"
    data = one(text).data
    assert data["c"] == {"z": 3, "y": 2, "x": 1}
    assert data["d"] == {"w": 0}


def test_a_quoted_merge_key_is_an_ordinary_key() -> None:
    assert one('"<<": 1\n').data == {"<<": 1}


def test_yaml_1_1_scalars_are_kept_and_dates_stay_text() -> None:
    document = one("a: yes\nb: off\nc: 2021-03-04\nd: 0x1F\ne: 1e3\nf: 1.5e+3\ng: '1.0'\nh: ~\n")
    assert document.data == {
        "a": True,
        "b": False,
        "c": "2021-03-04",
        "d": 31,
        "e": "1e3",
        "f": 1500.0,
        "g": "1.0",
        "h": None,
    }


def test_several_documents_and_stray_separators() -> None:
    documents = load_yaml_text("---\n---\na: 1\n---\n- 2\n---\n")
    assert [d.data for d in documents] == [{"a": 1}, [2]]
    assert documents[1].locate((0,)) == (5, 3)
    # An explicit null is a document; only an empty one is skipped.
    assert [d.data for d in load_yaml_text("~\n")] == [None]


@pytest.mark.parametrize("text", ["", "\n\n", "# only\n  # comments\n", "---\n", "--- \n...\n"])
def test_a_file_without_documents_is_an_error(text: str) -> None:
    errors = errors_of(text)
    assert where(errors) == [(1, 1, "")]
    assert errors[0].message.startswith("file is empty: ")


def billion_laughs(levels: int = 9) -> str:
    lines = ["l0: &l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    for level in range(1, levels):
        aliases = ", ".join([f"*l{level - 1}"] * 9)
        lines.append(f"l{level}: &l{level} [{aliases}]")
    return "\n".join(lines) + "\n"


def test_billion_laughs_fails_fast_at_the_alias_that_breaks_the_budget() -> None:
    # CPU time of this process, not wall time (which a loaded machine inflates): the guard is
    # against expanding the aliases first (minutes, gigabytes), not a speed target.
    started = time.process_time()
    errors = errors_of(billion_laughs())
    assert time.process_time() - started < 1.0
    # l5 holds 1 + 9 * (1 + 9 * (...)) = 597871 values; the lines before hold 672609 values with
    # keys, so the file passes 1 000 000 values at the first *l5 in line 7.
    assert where(errors) == [(7, 10, "")]
    assert errors[0].message == (
        "alias *l5 expands to 597871 values and the file exceeds the limit of 1000000 values"
    )


def test_node_limit_counts_plain_values_too() -> None:
    # The root mapping, a, the list, 1: four values; the 2 is the fifth.
    errors = errors_of("a: [1, 2, 3, 4]\n", max_nodes=4)
    assert where(errors) == [(1, 8, "")]
    assert errors[0].message == "the file exceeds the limit of 4 values"


@pytest.mark.parametrize(
    ("text", "position"),
    [
        ("[" * 10_000 + "]" * 10_000, (1, 65)),
        ("{a: " * 10_000 + "1" + "}" * 10_000, (1, 257)),
        ("- " * 10_000 + "x\n", (1, 129)),
        # Line n holds the mapping n levels deep, indented n - 1 spaces.
        ("a:\n" + "".join(" " * level + "b:\n" for level in range(1, 3_000)), (65, 65)),
    ],
    ids=["flow lists", "flow mappings", "block lists", "block mappings"],
)
def test_deep_nesting_fails_fast_without_recursion_error(
    text: str, position: tuple[int, int]
) -> None:
    started = time.process_time()  # CPU time, as above
    errors = errors_of(text)
    assert time.process_time() - started < 2.0
    assert where(errors) == [(*position, "")]
    assert errors[0].message == "nesting deeper than 64 levels"


def test_depth_counts_through_aliases() -> None:
    assert one("a: &a [[1]]\nb: [*a]\n").data["b"] == [[[1]]]
    # b's list is level 2 and its inner list 3; *a adds two more: 5 levels.
    errors = errors_of("a: &a [[1]]\nb: [[*a]]\n", max_depth=4)
    assert where(errors) == [(2, 6, "")]
    assert errors[0].message == "alias *a nests deeper than 4 levels here"


def test_text_beyond_the_byte_limit_is_refused() -> None:
    errors = errors_of("a: é\n", max_bytes=5)  # five characters, six bytes
    assert where(errors) == [(1, 1, "")]
    assert errors[0].message == "file is larger than the limit of 5 bytes"


def test_limits_cannot_be_set_beyond_what_is_safe() -> None:
    with pytest.raises(ValueError, match="max_depth"):
        load_yaml_text("a: 1\n", max_depth=10_000)


def test_load_yaml_reads_a_file(tmp_path: Path) -> None:
    path = tmp_path / "fabric.yaml"
    path.write_text("name: plain\n---\nname: twill\n", encoding="utf-8")
    documents = load_yaml(path)
    assert [d.data for d in documents] == [{"name": "plain"}, {"name": "twill"}]
    assert documents[1].file == str(path)
    assert documents[1].locate(("name",)) == (3, 1)


def test_a_byte_order_mark_and_crlf_line_ends_are_accepted(tmp_path: Path) -> None:
    path = tmp_path / "windows.yaml"
    path.write_bytes(b"\xef\xbb\xbfa: 1\r\nb: [1,\r\n  .nan]\r\n")
    with pytest.raises(YamlSourceError) as caught:
        load_yaml(path)
    assert where(caught.value.errors) == [(3, 3, "b[1]")]


def test_bytes_that_are_not_utf8_are_located(tmp_path: Path) -> None:
    path = tmp_path / "latin1.yaml"
    path.write_bytes("a: 1\nb: café\nc: ok\n".encode("latin-1") + b"d: \xff\xfe\n")
    with pytest.raises(YamlSourceError) as caught:
        load_yaml(path)
    assert [(e.line, e.column) for e in caught.value.errors] == [(2, 7), (4, 4), (4, 5)]
    assert caught.value.errors[0].message == (
        "not UTF-8: byte 0xe9 at byte offset 11; save the file as UTF-8"
    )


def test_missing_and_unreadable_files_are_errors(tmp_path: Path) -> None:
    for path, reason in [(tmp_path / "nope.yaml", "No such file"), (tmp_path, "directory")]:
        with pytest.raises(YamlSourceError) as caught:
            load_yaml(path)
        (error,) = caught.value.errors
        assert (error.file, error.line, error.column) == (str(path), 1, 1)
        assert error.message.startswith("cannot read file: ")
        assert reason in error.message


def test_a_file_beyond_the_byte_limit_is_refused_unread(tmp_path: Path) -> None:
    path = tmp_path / "big.yaml"
    path.write_text("a: " + "x" * 100 + "\n", encoding="utf-8")
    with pytest.raises(YamlSourceError) as caught:
        load_yaml(path, max_bytes=50)
    assert [e.message for e in caught.value.errors] == ["file is larger than the limit of 50 bytes"]


# JSON-like data: what fabric files hold. Surrogates cannot be written to a file as UTF-8;
# U+0085 is left out because PyYAML itself does not read back what it dumps for it
# (yaml.safe_dump({"\x85": 1}, allow_unicode=True) loads as {" ": 1}).
_text = st.text(st.characters(exclude_categories=["Cs"], exclude_characters="\x85"), max_size=12)
_scalars = (
    st.none()
    | st.booleans()
    | st.integers()
    | st.floats(allow_nan=False, allow_infinity=False)
    | _text
)
_json_like = st.recursive(
    _scalars,
    lambda children: st.lists(children, max_size=4) | st.dictionaries(_text, children, max_size=4),
    max_leaves=20,
)


def paths_of(data: Any, prefix: YamlPath = ()) -> list[YamlPath]:
    paths = [prefix]
    if isinstance(data, dict):
        for key, value in data.items():
            paths += paths_of(value, (*prefix, key))
    elif isinstance(data, list):
        for index, value in enumerate(data):
            paths += paths_of(value, (*prefix, index))
    return paths


@settings(max_examples=150, deadline=None)
@given(data=_json_like, flow=st.sampled_from([None, False, True]), unicode=st.booleans())
def test_dumped_data_loads_back_equal_and_every_path_is_located_in_the_text(
    data: Any, flow: bool | None, unicode: bool
) -> None:
    text = yaml.safe_dump(data, default_flow_style=flow, allow_unicode=unicode)
    (document,) = load_yaml_text(text)
    assert document.data == data
    lines = re.split("\r\n|[\n\r\x85\u2028\u2029]", text)  # line breaks as YAML counts them
    for path in paths_of(data):
        for line, column in (document.locate(path), document.locate_value(path)):
            assert 1 <= line <= len(lines)
            assert 1 <= column <= len(lines[line - 1]) + 1


def test_floats_round_trip_exactly() -> None:
    for value in (0.1, -0.0, 1e300, 5e-324, math.pi):
        (document,) = load_yaml_text(yaml.safe_dump({"x": value}))
        assert document.data["x"] == value


def _events(loader: type[Any], text: str) -> list[tuple[Any, ...]]:
    """A parser's events as plain tuples, marks as (line, column); a plain scalar's style is
    None in PyYAML and '' in libyaml, the same thing."""
    parser = loader(text)
    try:
        out = []
        while parser.check_event():
            e = parser.get_event()
            out.append(
                (
                    type(e).__name__,
                    getattr(e, "value", None),
                    getattr(e, "implicit", None),
                    getattr(e, "anchor", None),
                    getattr(e, "tag", None),
                    getattr(e, "style", None) or None,
                    (e.start_mark.line, e.start_mark.column),
                    (e.end_mark.line, e.end_mark.column),
                )
            )
        return out
    finally:
        parser.dispose()


PROJECT_YAML = sorted(
    p
    for p in Path(__file__).resolve().parents[1].glob("**/*.yaml")
    if not any(part.startswith(".") for part in p.parts)
)


@pytest.mark.skipif(not yaml.__with_libyaml__, reason="PyYAML built without libyaml")
@pytest.mark.parametrize("path", PROJECT_YAML, ids=lambda p: p.name)
def test_libyaml_events_are_pyyaml_events_on_the_project_files(path: Path) -> None:
    """libyaml only reads faster: on every YAML file of the project (library, scenes, tools,
    examples) its events and their marks are PyYAML's, non-ASCII text included."""
    text = path.read_text(encoding="utf-8")
    assert _events(yaml.CSafeLoader, text) == _events(yaml.SafeLoader, text)


@pytest.mark.skipif(not yaml.__with_libyaml__, reason="PyYAML built without libyaml")
@settings(max_examples=60, deadline=None)
@given(
    st.recursive(
        st.none() | st.booleans() | st.integers() | st.text(max_size=8),
        lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=6), inner),
        max_leaves=12,
    ),
    st.booleans(),
)
def test_libyaml_and_pyyaml_agree_on_dumped_data(data: Any, flow: bool) -> None:
    text = yaml.safe_dump({"entry": data}, default_flow_style=flow, allow_unicode=True)
    assert _events(yaml.CSafeLoader, text) == _events(yaml.SafeLoader, text)
