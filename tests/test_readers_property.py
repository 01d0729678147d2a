"""Property: every reader of acid (HDF5 datasets, CSV and MAT imports, channel maps,
params.json, econ parameters, the plant configuration TOML, sweep specifications, FMU maps,
summary.json, sweep scenario records) refuses damaged or foreign files, also nested thousands
of levels deep, with acid's own one-line error (``AcidError``) and nothing else.

Example counts come from the hypothesis profile (``tests/conftest.py``): ``acid-ci`` (150 per
reader, the default) or ``--hypothesis-profile=acid-thorough`` (1,500 per reader).
"""

from __future__ import annotations

import pytest
from _fuzz import READERS, read_example
from hypothesis import given

from acid.errors import AcidError


@pytest.mark.parametrize("name", list(READERS))
def test_reader_raises_only_acid_errors(name, tmp_path):
    reader = READERS[name]

    @given(reader.files)
    def reading_never_escapes(example):
        try:
            read_example(reader, example, tmp_path)
        except AcidError as exc:
            assert "\n" not in str(exc)

    reading_never_escapes()
