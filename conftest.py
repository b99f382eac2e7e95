"""pytest set-up shared by the tests and the docstring examples (collected from src/whipple_kick)."""
import pytest


@pytest.fixture(autouse=True)
def _examples_run_in_a_temporary_folder(request, tmp_path, monkeypatch):
    """Docstring examples that write files (``animate(result, "kick.gif")``) write them into a temporary folder."""
    if isinstance(request.node, pytest.DoctestItem):
        monkeypatch.chdir(tmp_path)
