"""Uncertainty propagation, global sensitivity and survival on stochastic ground (``biped-sim uncertainty``).

Modules, each about one thing: :mod:`.distributions` (what is known of a key, parsed), :mod:`.sampling` (the
design in the unit cube), :mod:`.samples` (the runs, chunked and resumable), :mod:`.statistics`, :mod:`.sobol`
(the indices), :mod:`.study` (the study itself), :mod:`.files` (its HDF5 and CSV) and :mod:`.mfpt` (the mean
first-passage time on random ground).
"""
