"""Deep YAML is refused with omnirender's own message whatever the installed PyYAML/libyaml does.

libyaml (PyYAML's fast parser) has nesting limits of its own in newer versions, worded its own way and
checked while it scans ahead of the composer; these tests hold the reader to its own limits both with
libyaml and without it, and with a fast parser that refuses the document for reasons of its own.
"""

from __future__ import annotations

import pytest
import yaml

from omnirender.scene import files, parse
from omnirender.scene.files import SceneFileError
from omnirender.scene.parse import ParseError, ParseLimits


@pytest.mark.parametrize("pure", [False, True])
@pytest.mark.parametrize("depth", [257, 2000, 100_000])
def test_flow_nesting_is_refused_by_either_parser_with_the_path(pure, depth, monkeypatch):
    if pure:  # the pure-Python parser only (as where PyYAML is built without libyaml)
        monkeypatch.setitem(parse._LOADERS, False, parse._loader_class(pure=True))
    text = "x: " + "[" * depth + "]" * depth + "\n"
    with pytest.raises(ParseError, match="nested deeper than 256 levels") as info:
        parse.parse_yaml(text)
    assert info.value.path.startswith("x[0][0]") and info.value.path.count("[0]") == 255


def test_a_fast_parser_refusing_on_its_own_terms_is_read_again_by_the_pure_one(monkeypatch):
    class Refusing:  # a libyaml with a nesting limit below omnirender's, worded its own way
        def __init__(self, text: str) -> None:
            pass

        def get_single_data(self):
            raise yaml.YAMLError("while increasing flow level exceeded maximum nesting depth")

        def dispose(self) -> None:
            pass

    monkeypatch.setitem(parse._LOADERS, False, Refusing)
    with pytest.raises(SceneFileError, match="nested deeper than 8 levels"):
        files.loads("x: " + "[" * 20 + "]" * 20 + "\n", "yaml", limits=ParseLimits(max_depth=8))
    # a document within omnirender's limits still loads: the pure parser's answer stands
    assert parse.parse_yaml("a: [[1], {b: 2}]\n") == {"a": [[1], {"b": 2}]}
    # and a document that is invalid YAML keeps the fast parser's error
    with pytest.raises(yaml.YAMLError, match="exceeded maximum nesting depth"):
        parse.parse_yaml("a: [\n")


def test_block_nesting_is_refused_with_omnirenders_message():
    text = "".join("  " * i + "- \n" for i in range(3000))
    with pytest.raises(ParseError, match="nested deeper than 256 levels"):
        parse.parse_yaml(text)
