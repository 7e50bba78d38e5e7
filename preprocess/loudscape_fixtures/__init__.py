"""Test support, not shipped: the generators of the fixtures the readers of the format test
against (``song``: data/fixture_song.ply; ``formats``: tests/fixtures/format/). Installed by
the development venv (preprocess/pyproject.toml); the wheel (the root pyproject.toml) leaves
it out.
"""
