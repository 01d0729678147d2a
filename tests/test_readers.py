"""``acid._readers``: TOML and JSON files read with a size limit and a depth limit, one line
naming the file (and the key where there is one)."""

from __future__ import annotations

import pytest

from acid._readers import MAX_DEPTH, check_tree, load_json, load_toml, nesting_depth
from acid.errors import ConfigError, DataError


def test_depth_scan_skips_strings_and_comments():
    assert nesting_depth('{"a": [1, "[[[[", {"b": "]]}}"}]}') == 3
    assert nesting_depth('x = "[[["  # [[[[\ny = \'[[\'\nz = """\n[[[\n"""\n', toml=True) == 0
    assert nesting_depth('x = [[1], [2]]\n[t]\n[[arr]]\n', toml=True) == 2
    assert nesting_depth('{"a": "\\\\"}') == 1  # an escaped backslash ends the string


def test_deep_documents_are_refused_before_parsing(tmp_path):
    f = tmp_path / "d.json"
    f.write_text('{"a": ' + "[" * 200_000 + "]" * 200_000 + "}")
    with pytest.raises(DataError, match=r"d.json: JSON file nests 200001 levels deep \(at most"):
        load_json(f)
    t = tmp_path / "d.toml"
    t.write_text("a = " + "{ b = " * 40 + "1" + " }" * 40 + "\n")
    with pytest.raises(ConfigError, match="d.toml: TOML file nests 40 levels"):
        load_toml(t)
    t.write_text("a" + ".b" * (MAX_DEPTH + 1) + " = 1\n")  # no brackets: found in the tree
    with pytest.raises(ConfigError, match=r"d.toml: a\.b\.b.* nests deeper than 32 levels"):
        load_toml(t)
    at_limit = "x = " + "[" * MAX_DEPTH + "]" * MAX_DEPTH + "\n"
    t.write_text(at_limit)
    assert load_toml(t)["x"]


def test_size_encoding_syntax_and_top_level_are_one_line(tmp_path):
    f = tmp_path / "f.json"
    f.write_text('{"a": "' + "x" * 3000 + '"}')
    with pytest.raises(DataError, match="f.json: JSON file is larger than"):
        load_json(f, max_bytes=2048)
    f.write_bytes(b'{"a": "\xff"}')
    with pytest.raises(DataError, match=r"f.json: not valid JSON \(not UTF-8 text at byte 7\)"):
        load_json(f)
    f.write_text('{"a": [1.0, {"b": NaN}]}')
    with pytest.raises(DataError, match=r"f.json: a\[1\]\.b = nan is a non-finite number"):
        load_json(f)
    f.write_text("[1]")
    with pytest.raises(DataError, match="must be a JSON object at the top level, got an array"):
        load_json(f)
    assert load_json(f, top=None) == [1]
    with pytest.raises(ConfigError, match="none.toml: spec not found"):
        load_toml(tmp_path / "none.toml", "spec")
    with pytest.raises(ConfigError, match=f"{tmp_path}: spec is not a file"):
        load_toml(tmp_path, "spec")
    t = tmp_path / "bad.toml"
    t.write_text("a = \n")
    with pytest.raises(ConfigError, match=r"bad.toml: not valid TOML \("):
        load_toml(t)


def test_check_tree_names_the_key_path():
    tree: dict = {"ok": 1, "l": [{"m": {}}]}
    check_tree(tree, "src", max_depth=3)
    with pytest.raises(DataError, match=r"src: l\[0\]\.m nests deeper than 2 levels"):
        check_tree(tree, "src", max_depth=2)
