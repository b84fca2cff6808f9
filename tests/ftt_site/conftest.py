import pytest

from tests.support.directory import running_directory


@pytest.fixture(scope="module")
def directory(tmp_path_factory):
    """A real slapd for one test module (tests.support.directory)."""
    with running_directory(tmp_path_factory.mktemp("directory")) as found:
        yield found
