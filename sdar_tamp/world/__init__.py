"""The dual-arm world: scene, kinematics, collision, rearrangement instances.

Light modules are re-exported here; the pinocchio/coal ones are imported from their modules:
:mod:`.kinematics` (``ArmKinematics``), :mod:`.collision` (``CollisionWorld``),
:mod:`.dls_ik`, :mod:`.ur_ik` (batched closed form, numpy only), :mod:`.draw` (matplotlib).
"""

from sdar_tamp.world.dependency import DependencyGraph, Structure, instance_dependency_graph
from sdar_tamp.world.errors import (
    ArmLayoutError,
    CollisionModelError,
    GenerationError,
    InstanceError,
    KinematicsError,
    SceneError,
    SuiteError,
    WorldError,
    WorldFileError,
)
from sdar_tamp.world.generators import FAMILIES, GeneratorOptions, generate_instance
from sdar_tamp.world.instance import (
    Instance,
    ObjectSpec,
    Pose2D,
    dump_instance,
    load_instance,
    parse_instance,
    save_instance,
    validate_instance,
)
from sdar_tamp.world.layout import ArmLayout
from sdar_tamp.world.scene import ArmSpec, Gripper, Scene, Table, Workspace, load_scene
from sdar_tamp.world.suites import SUITES, build_suite, generate_suite, load_suite

__all__ = [
    "FAMILIES",
    "SUITES",
    "ArmLayout",
    "ArmLayoutError",
    "ArmSpec",
    "CollisionModelError",
    "DependencyGraph",
    "GenerationError",
    "GeneratorOptions",
    "Gripper",
    "Instance",
    "InstanceError",
    "KinematicsError",
    "ObjectSpec",
    "Pose2D",
    "Scene",
    "SceneError",
    "Structure",
    "SuiteError",
    "Table",
    "Workspace",
    "WorldError",
    "WorldFileError",
    "build_suite",
    "dump_instance",
    "generate_instance",
    "generate_suite",
    "instance_dependency_graph",
    "load_instance",
    "load_scene",
    "load_suite",
    "parse_instance",
    "save_instance",
    "validate_instance",
]
