"""The FMU tests build the units of fmus/ into build/fmus (helpers.FMU_CACHE), once per content for every test
and process, not into the user's cache."""

import pytest
from helpers import FMU_CACHE


@pytest.fixture(scope="module", autouse=True)
def fmu_cache():
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("ICOSIM_FMU_CACHE", str(FMU_CACHE))
        yield FMU_CACHE
