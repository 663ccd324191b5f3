"""SDAR-M's synchronous multi-arm motion planner, one concept per module.

Import from the modules (this package imports nothing, so that :mod:`streams.context` can
use the symbolic kinematics without loading the planner):

* the planner and one segment: :mod:`~streams.motion.planner` (:class:`MotionPlanner`),
  :mod:`~streams.motion.ladder` (:func:`plan_dual_motion`, the strategies tried in turn),
  :mod:`~streams.motion.records` (:class:`MotionRequest`, :class:`MotionResult`);
* the transfer: :mod:`~streams.motion.strategies`, :mod:`~streams.motion.transfers` (their
  building blocks), :mod:`~streams.motion.sampling` (OMPL), :mod:`~streams.motion.phases`
  (retreat and approach), :mod:`~streams.motion.assembly` (timing and blending),
  :mod:`~streams.motion.shape`, :mod:`~streams.motion.timing`,
  :mod:`~streams.motion.cartesian`, :mod:`~streams.motion.waypoints`;
* the trajectory optimiser: :mod:`~streams.motion.optimiser` (:class:`TrajectoryOptimiser`),
  :mod:`~streams.motion.optimiser_records` (:class:`TrajOptOptions`), its NLP
  (:mod:`~streams.motion.nlp`), sphere slots (:mod:`~streams.motion.slots`), the moving
  arms' own problem when others wait (:mod:`~streams.motion.subsets`), background
  build and cache (:mod:`~streams.motion.optimiser_build`,
  :mod:`~streams.motion.optimiser_cache`), compiled derivatives
  (:mod:`~streams.motion.codegen`);
* the geometry: :mod:`~streams.motion.spheres`, :mod:`~streams.motion.sphere_pairs`, the
  CasADi forward kinematics :mod:`~streams.motion.fk_casadi`, the exact trajectory check
  :mod:`~streams.motion.exact_check`.
"""
