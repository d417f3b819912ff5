"""A rigid walker in space's first run compiled on two cores: the stance phase's callees split between a second process
and the run's (:func:`~biped_sim.simulate.aside.prepare_compiling_aside` forks the process).

A cold rigid run in space compiles, in one process, the limit cycle's clearance twin (the feet's rotations and
lowest points) and then the stance phase's twin (:func:`~biped_sim.rigid.space_integration.space_phase`, some four
fifths of its compile): the flow (:func:`~biped_sim.rigid.space_kernels.space_flow`), the events, a step's attempt
and the accepted step's bookkeeping (event location on the dense output, samples). Below the phase its callees form
two trees that share only the feet's rotations, the stance foot's lowest point and the swing shank's frame: the
flow's (a leg's terms of Kane's equations, the contact point's rate, the flow, a step's attempt and the dense
output's extra stages over it) and the events' (the fall function, the clearance, the guard, their root on the dense
output, the samples). The run's process compiles the rotations first (:func:`first_callee`; loaded on a warm cache,
which starts no process), then a second process compiles the flow's tree (:func:`flow_share`) while this one
compiles the events' (:func:`events_share`, the stance foot's lowest point first: the flow's compile reaches it
after a leg's terms and the contact point's rate) and the clearance's twin (:func:`clearance_twin`). The phase's
twin, compiled once both are done, compiles only itself, the accepted step's bookkeeping (which calls both trees)
inlined in it. The arguments are stand-ins of the types the callers pass (the model is a flat parameter vector:
every walker in space compiles the same code); none is called.

The run's measures (its samples in the run's frame, the step table, the files) are plain numpy: they compile nothing.
"""

from __future__ import annotations

import numpy as np
from numba.core.dispatcher import Dispatcher

from biped_sim.integrate.dense import sample_dense
from biped_sim.kernel import Kernel
from biped_sim.rigid.space_integration import (
    SpaceScratch,
    _attempt,
    _events,
    _prepare_dense,
    _root,
    space_clearance,
    space_fall,
    space_scratch,
)
from biped_sim.rigid.space_kernels import (
    N_PARAMS,
    _add_part,
    contact_rate,
    knee_frame,
    rotations,
    space_flow,
    torso_elements,
)
from biped_sim.rigid.space_model import N_STATE

Callee = tuple[Dispatcher, tuple[object, ...]]

STAND_IN_SAMPLES = 2  # the record's room: its arrays' types only


def _stand_ins() -> tuple[np.ndarray, np.ndarray, SpaceScratch]:
    """A parameter vector, a state and the integration's scratch with a record: the types the phase passes."""
    return np.zeros(N_PARAMS), np.zeros(N_STATE), space_scratch(STAND_IN_SAMPLES)


def first_callee() -> Callee:
    """The feet's rotations with their argument's type: the first callee both shares reach, compiled before the
    fork; on a warm cache loaded, which says no fork is worth it."""
    _, x, _ = _stand_ins()
    return rotations, (x,)


def flow_share() -> tuple[Callee, ...]:
    """The second process's share: a leg's terms of Kane's equations, the contact point's rate, a torso's elements,
    the flow (the stance
    foot's lowest point loaded from the run's process by then), a step's attempt and the dense output's extra stages,
    with their arguments' types."""
    p, x, (tab, sc, _) = _stand_ins()
    turn, v = np.zeros((3, 3)), np.zeros(3)
    return (
        (_add_part, (p, 0, np.zeros(4), turn, v, v, np.zeros((5, 3)), v, np.zeros((4, 4)), np.zeros(4))),
        (contact_rate, (p, turn, v, v)),
        (torso_elements, (p, x)),
        (space_flow, (p, x)),
        (_attempt, (p, tab, sc, 0.0, x)),
        (_prepare_dense, (p, tab, sc, 0.0, x)),
    )


def events_share() -> tuple[Callee, ...]:
    """The run's process's share, meanwhile: the fall function (the stance foot's lowest point, which the flow calls
    too, first), the swing shank's frame (the flow's too, which reaches it after a leg's terms), the swing foot's
    clearance, the events, their root on the dense output and the samples, with their
    arguments' types."""
    p, x, (tab, sc, rec) = _stand_ins()
    return (
        (space_fall, (p, 0.0, x)),
        (knee_frame, (p, x, np.zeros((3, 3)))),
        (space_clearance, (p, x)),
        (_events, (p, 0, 0.0, x, sc.g_new)),
        (_root, (p, tab, sc, 0, 0.0, 0, 0.0, 0.0, x)),
        (sample_dense, (tab, sc, 0.0, 0, 0.0, 0.0, 0.0, x, rec.samples_t, rec.samples_x, 0)),
    )


def clearance_twin() -> tuple[Kernel, tuple[object, ...]]:
    """The clearance's twin (the limit cycle's section calls it from Python) with its arguments' types."""
    p, x, _ = _stand_ins()
    return space_clearance, (p, x)
