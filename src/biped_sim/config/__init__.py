"""Configuration: the one place where defaults, units and validation rules live.

All quantities are SI (m, kg, s, N, Pa) and angles are radians. The schema (:mod:`.schema`) maps
one-to-one onto the YAML files in ``configs/``; unknown keys are errors so that a typo is never
silently ignored. ``load_config`` (:mod:`.loading`) reads YAML (with a YAML-1.2-style float resolver
so that ``1e7`` is a number), applies ``--set key=value`` overrides and validates; every failure
becomes a :class:`~biped_sim.errors.ConfigError` naming the dotted field and the reason.
"""

from biped_sim.config.base import is_number_annotation
from biped_sim.config.description import (
    LEG_KEYS,
    STATE_KEYS,
    BodySpec,
    JointSpec,
    PointMassSpec,
    StopSpec,
    WalkerDescription,
)
from biped_sim.config.feet import FootSpec
from biped_sim.config.loading import (
    apply_override,
    config_from_dict,
    default_output_dir,
    derive,
    get_dotted,
    load_config,
    parse_yaml,
    read_text_file,
    set_dotted,
)
from biped_sim.config.schema import (
    BaumgarteConfig,
    Config,
    ContactConfig,
    FormulationConfig,
    FrictionConfig,
    GroundConfig,
    InitialState,
    IntegratorConfig,
    MaterialConfig,
    MaterialsConfig,
    OutputConfig,
    Push,
    SimulationConfig,
)
from biped_sim.config.walker_schema import (
    CompassWalker,
    DescribedWalker,
    FourLeggedWalker,
    RimlessWheelWalker,
    SimplestWalker,
    WalkerConfig,
)

__all__ = [
    "LEG_KEYS",
    "STATE_KEYS",
    "BaumgarteConfig",
    "BodySpec",
    "CompassWalker",
    "Config",
    "ContactConfig",
    "DescribedWalker",
    "FootSpec",
    "FormulationConfig",
    "FourLeggedWalker",
    "FrictionConfig",
    "GroundConfig",
    "InitialState",
    "IntegratorConfig",
    "JointSpec",
    "MaterialConfig",
    "MaterialsConfig",
    "OutputConfig",
    "PointMassSpec",
    "Push",
    "RimlessWheelWalker",
    "SimplestWalker",
    "SimulationConfig",
    "StopSpec",
    "WalkerConfig",
    "WalkerDescription",
    "apply_override",
    "config_from_dict",
    "default_output_dir",
    "derive",
    "get_dotted",
    "is_number_annotation",
    "load_config",
    "parse_yaml",
    "read_text_file",
    "set_dotted",
]
