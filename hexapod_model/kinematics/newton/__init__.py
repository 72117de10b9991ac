"""The one Newton iteration that closes the loops, and the three paths that run it.

One step, whatever the path: the closure frames and joint Jacobians at ``q``, the residual
(Bem et al. (2026) eqs. 10-14) and its exact Jacobian (:mod:`.kernels`), the structured linear
solve (:mod:`.structured`: the Schur elimination for direct kinematics, leg blocks for inverse
kinematics; :mod:`.linalg`: dense LU for any held set), and the step on the configuration
manifold. The paths:

* **general** — :class:`.solver.NewtonSolver`: Pinocchio computes the frames and Jacobians, any
  held set (hybrid problems), kernels from :mod:`.kernel_sets`;
* **NumPy** — the same solver with :mod:`.numpy_kernels` (``compiled=False``): no numba;
* **compiled** — :class:`.compiled.CompiledSolver`: the whole iteration in one numba call
  (:mod:`.iteration`), the chains evaluated from the Pinocchio model (:mod:`.chains`,
  :mod:`.legs`, :mod:`.lie`), tables and buffers packed in flat arrays (:mod:`.packing`) and
  cut into shaped views inside the compiled code (:mod:`.views`); the readings path
  (:mod:`.follow`) and the batch loops (:mod:`.batch_kernels`) run compiled too.

:mod:`.outcomes` names the outcome codes; :mod:`.path_rules` the readings path's step rules.

Beside the iteration, the proof of a warm step: :mod:`.proof` (:class:`.proof.Proof`,
:class:`.proof.StepProver`) runs the compiled Krawczyk test of :mod:`.krawczyk` on interval
enclosures of the residual and its Jacobian (:mod:`.intervals`, rounding bounded).
"""
