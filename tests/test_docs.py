"""The documentation: the scene-file reference is generated from the code's key tables,
and every key is named in its section's text."""
import re

from skfem_beam import scenedocs


def words_in_code(text: str) -> set[str]:
    """The names inside `backticks` of a Markdown text."""
    return set(re.findall(r"[A-Za-z_][A-Za-z_0-9]*", " ".join(re.findall(r"`([^`]*)`", text))))


def test_every_scene_file_key_is_documented():
    sections = scenedocs.sections()
    assert set(sections) == set(scenedocs.SECTION_DOCS)
    missing = []
    for name, kinds in sections.items():
        named = words_in_code(scenedocs.SECTION_DOCS[name])
        for keys in kinds.values():
            for key in keys:
                parts = key.split(".")
                # a sub-table named after another section is documented there
                word = parts[0] if len(parts) > 1 and parts[0] in sections else parts[-1]
                if word not in named:
                    missing.append(f"[{name}] {key}")
    assert not missing, missing


def test_the_reference_lists_every_key_of_the_code():
    from skfem_beam.scenefile import BAR_KEYS, BEAM_KEYS
    text = scenedocs.reference()
    for schema in (BEAM_KEYS, BAR_KEYS):
        for key in schema:
            assert f"`{key}`" in text or f"[{key}]" in text, key
    assert text.count("\n") == len(scenedocs.sections()) + 2


def test_the_committed_key_page_is_the_code_s():
    """docs/scene_keys.md reads on GitHub: it must be what the code's tables give."""
    from pathlib import Path
    page = Path(__file__).parent.parent / scenedocs.PAGE
    assert page.read_text() == scenedocs.page(), "run the docs build to rewrite it"
