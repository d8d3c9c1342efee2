"""The package's YAML loader (safe_yaml.py): every refusal is one line naming the file (and line)."""
import re
from pathlib import Path

import pytest

from snake_autonomy.safe_yaml import MAX_FILE_BYTES, YamlFileError, load_yaml_file, load_yaml_text


def refused(tmp_path, data: bytes) -> str:
    f = tmp_path / "f.yaml"
    f.write_bytes(data)
    with pytest.raises(YamlFileError) as info:
        load_yaml_file(f)
    message = str(info.value)
    assert message.startswith(f"{f}: ") and "\n" not in message, message
    return message


def test_ordinary_files_load(tmp_path):
    f = tmp_path / "ok.yaml"
    f.write_text("a: 1\nb: [1, 2, {c: x}]\nemoji: \"\u00e9\"\n", encoding="utf-8")
    assert load_yaml_file(f) == {"a": 1, "b": [1, 2, {"c": "x"}], "emoji": "\u00e9"}
    assert load_yaml_text("") is None


def test_files_that_are_not_utf8_text(tmp_path):
    assert "not a text file (NUL byte at offset" in refused(tmp_path, bytes(range(256)))
    assert "not UTF-8 text (a UTF-16/UTF-32 byte-order mark)" in refused(tmp_path, "a: 1\n".encode("utf-16"))
    assert "not UTF-8 text (byte 0xff at offset 3)" in refused(tmp_path, b"a: \xff\n")


def test_size_bound(tmp_path):
    assert f"larger than {MAX_FILE_BYTES} bytes" in refused(tmp_path, b"#" * (MAX_FILE_BYTES + 1))


def test_aliases_and_anchors_are_refused(tmp_path):
    laughs = b"a: &a [lol, lol]\nb: [*a, *a]\n"
    assert "line 1: anchor &a refused" in refused(tmp_path, laughs)
    with pytest.raises(YamlFileError, match="alias \\*x refused"):
        load_yaml_text("b: *x\n")


def test_duplicate_keys_name_the_key_and_both_lines(tmp_path):
    msg = refused(tmp_path, b"name: m\nwaypoints: [[1, 0, 0]]\nwaypoints: [[2, 0, 0]]\n")
    assert "line 3: duplicate key 'waypoints' (first given on line 2)" in msg
    msg = refused(tmp_path, b"a:\n  x: 1\n  y: 2\n  x: 3\n")
    assert "line 4: duplicate key 'x' (first given on line 2)" in msg


def test_nesting_is_bounded(tmp_path):
    assert "nested deeper than 32 levels" in refused(tmp_path, b"a: " + b"[" * 50000 + b"]" * 50000)
    nested = load_yaml_text("a: " + "[" * 30 + "]" * 30)["a"]
    for _ in range(29):
        nested = nested[0]
    assert nested == []


def test_syntax_errors_are_one_line_with_the_position(tmp_path):
    assert "not valid YAML: line 2, column" in refused(tmp_path, b"a: [1, 2\nb: }\n")


def test_missing_file_and_folder(tmp_path):
    with pytest.raises(FileNotFoundError):
        load_yaml_file(tmp_path / "nope.yaml")
    with pytest.raises(YamlFileError, match="is a folder"):
        load_yaml_file(tmp_path)


def test_every_yaml_the_package_reads_goes_through_this_loader():
    """PyYAML's own loaders expand aliases and keep the last of two equal keys: no module calls them,
    for files or for in-memory texts (a RunMission goal's mission_yaml) alike."""
    package = Path(__file__).resolve().parents[2] / "python" / "snake_autonomy"
    direct = re.compile(r"\byaml\.(safe_load|load|full_load|unsafe_load|load_all|safe_load_all|compose)\s*\(")
    offenders = [f"{path.relative_to(package)}:{number}: {line.strip()}"
                 for path in sorted(package.rglob("*.py")) if path.name != "safe_yaml.py"
                 for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
                 if direct.search(line)]
    assert offenders == []


def test_a_text_is_capped_like_a_file():
    with pytest.raises(YamlFileError, match=f"^goal: larger than {MAX_FILE_BYTES} bytes"):
        load_yaml_text("#" * (MAX_FILE_BYTES + 1), "goal")


def test_a_quoted_value_is_short_and_escaped():
    from snake_autonomy.safe_yaml import short_repr
    text = short_repr("\x1b[2J" + "A" * 500)
    assert "\x1b" not in text and "\\x1b" in text and "A" * 61 not in text and "(504 characters)" in text
    assert short_repr([1, 2]) == "[1, 2]" and len(short_repr(list(range(1000)))) < 90
