"""Many runs: sweeps and their store, the pressure recommendation, validation against
the thesis' measurements, the authors' code side by side, and the linear stability.
"""
