"""loudscape_extract.fft: scipy's pocketfft called as scipy.fft calls it, without importing
scipy.fft (its import was a tenth of a song's extraction): the same bits as scipy.fft."""

import subprocess
import sys

import numpy as np
import pytest
import scipy.fft

from loudscape_extract import fft


def test_the_pocketfft_module_is_loaded_without_scipy_fft():
    # A fresh interpreter: the extractor's import leaves scipy.fft out, and a later
    # `import scipy.fft` reuses the one pocketfft module.
    code = (
        "import sys\n"
        "import loudscape_extract.cli\n"
        "assert 'scipy.fft' not in sys.modules, 'scipy.fft imported'\n"
        "from loudscape_extract import fft\n"
        "assert fft._POCKETFFT is not None, 'pocketfft not found'\n"
        "mine = sys.modules['scipy.fft._pocketfft.pypocketfft']\n"
        "import numpy as np, scipy.fft\n"
        "from scipy.fft._pocketfft import basic\n"
        "assert basic.pfft is mine, 'a second pocketfft module'\n"
        "x = np.arange(10.0)\n"
        "assert np.array_equal(scipy.fft.rfft(x), fft.rfft(x))\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


@pytest.mark.parametrize("dtype", [np.float32, np.float64, np.float16, np.int16])
@pytest.mark.parametrize("n", [None, 1, 7, 64, 1000, 4096])
@pytest.mark.parametrize("axis", [0, 1, -1])
def test_rfft_and_irfft_equal_scipy_fft_bit_for_bit(dtype, n, axis):
    rng = np.random.default_rng(7)
    x = (rng.standard_normal((64, 300)) * 100).astype(dtype)
    assert fft._POCKETFFT is not None
    ours = fft.rfft(x, n, axis=axis)
    theirs = scipy.fft.rfft(x, n, axis=axis)
    assert ours.dtype == theirs.dtype and ours.shape == theirs.shape
    assert np.array_equal(ours, theirs)
    m = None if n is None else max(n, 2)
    back, back_scipy = fft.irfft(ours, m, axis=axis), scipy.fft.irfft(theirs, m, axis=axis)
    assert back.dtype == back_scipy.dtype and np.array_equal(back, back_scipy)


def test_real_input_to_irfft_and_bad_sizes_behave_as_scipy():
    x = np.linspace(-1.0, 1.0, 33, dtype=np.float32)
    assert np.array_equal(fft.irfft(x), scipy.fft.irfft(x))
    assert np.array_equal(fft.irfft(x, 10), scipy.fft.irfft(x, 10))
    for call in (lambda: fft.rfft(x, 0), lambda: fft.rfft(np.zeros(0))):
        with pytest.raises(ValueError):
            call()
    with pytest.raises(TypeError):
        fft.rfft(x + 1j)


def test_without_pocketfft_scipy_fft_does_the_work(monkeypatch):
    monkeypatch.setattr(fft, "_POCKETFFT", None)
    x = np.arange(16.0)
    assert np.array_equal(fft.rfft(x, 8), scipy.fft.rfft(x, 8))
    assert np.array_equal(fft.irfft(fft.rfft(x)), scipy.fft.irfft(scipy.fft.rfft(x)))
