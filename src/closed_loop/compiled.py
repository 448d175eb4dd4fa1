"""The package's compiled loops (``sim.planar_kernel``, ``sim.footprint_kernel``, ``control.wave_kernel``,
``control.arc_kernel``, ``control.hybrid_kernel``) are compiled by numba with :func:`jit`: kept in
``__pycache__`` beside the source (or numba's cache directory in the user's home where that cannot be
written), so a process loads them in a fraction of a second; compiled afresh in each process, with the same results, where neither can be written (a read-only
install run by a user with no writable home). IEEE arithmetic (a division by zero is inf, as in numpy) and no
reordering of float operations, so a compiled loop gives numpy's results to the bit."""
import numba


def jit(function):
    """``function`` compiled with numba, its machine code cached where a place can be written."""
    try:
        return numba.njit(cache=True, nogil=True, error_model='numpy')(function)
    except RuntimeError:         # numba: "cannot cache function ...: no locator available"
        return numba.njit(nogil=True, error_model='numpy')(function)
