"""Uncertainty propagation, global sensitivity and survival on stochastic ground (``biped-sim uncertainty``,
``biped-sim mfpt``).

Modules, each about one thing: :mod:`.distributions` (what is known of a key, parsed), :mod:`.sampling` (the
design in the unit cube), :mod:`.samples` (the runs, chunked and resumable), :mod:`.statistics`, :mod:`.sobol`
(the indices), :mod:`.surrogate` (a polynomial-chaos estimate of them), :mod:`.study` (the study itself),
:mod:`.files` (its HDF5 and CSV), :mod:`.mfpt` (the mean first-passage time on random ground) with
:mod:`.rimless_chain` (the rimless wheel's Markov chain), and :mod:`.checks` (the known answers of
``biped-sim validate``).
"""
