"""``geometry``'s re-exports load on first use (issue 40 item 1): importing one light module
of the package (``geometry.validation``, which every layer's checks import) builds neither
the material registry nor the region table nor the presets, and each re-exported name is
its module's own object."""

import importlib

import pytest

import geometry

#: The modules a catalogue ``haptic`` or ``compare`` never uses, nor ``geometry.validation``.
REGISTRY_AND_TABLES = ("geometry.params", "geometry.materials", "geometry.regions",
                       "geometry.section", "geometry.reading")  # fmt: skip
#: Never loaded by those either; a design's command loads it only when the material cache
#: is cold (geometry.reading imports it where a TOML text is parsed: fb9f8eb).
TOML_PARSER = "tomllib"


@pytest.mark.parametrize("name", sorted(geometry.EXPORTS))
def test_each_export_is_its_modules_object(name: str) -> None:
    module = importlib.import_module(geometry.EXPORTS[name])
    assert getattr(geometry, name) is getattr(module, name)
    assert name in geometry.__all__


def test_an_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="module 'geometry' has no attribute 'presets'"):
        geometry.presets  # noqa: B018


def test_validation_and_the_catalogue_load_no_registry(fresh_python) -> None:
    """A fresh interpreter: ``geometry.validation`` alone, then the catalogue's ``haptic``
    and ``compare`` (no design named), load none of the registry's modules; a design's
    command does (the registry is read when a design is)."""
    code = (
        "import sys\nimport geometry.validation\n"
        "print(' '.join(sys.modules), file=sys.stderr)\n"
        "from mrclutch.cli.main import main\n"
        "for argv in (['haptic'], ['compare']):\n"
        "    assert main(argv) == 0, argv\n"
        "print('|', ' '.join(sys.modules), file=sys.stderr)\n"
        "assert main(['inertia', '--preset', 'paper', '--method', 'analytic']) == 0\n"
        "print('|', ' '.join(sys.modules), file=sys.stderr)"
    )
    alone, catalogue, design = (set(s.split()) for s in fresh_python(code).stderr.split("|"))
    assert "geometry.validation" in alone and "mrclutch.haptics.model" in catalogue  # they ran
    for name in REGISTRY_AND_TABLES:
        assert name not in alone, name
        assert name not in catalogue, name
        assert name in design, name
    assert TOML_PARSER not in alone and TOML_PARSER not in catalogue
