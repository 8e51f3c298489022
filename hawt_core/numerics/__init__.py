"""Numerics that know nothing about turbines: rotations and vector algebra, complex-step
Jacobians, Newton's method, descriptor-pencil eigen-analysis, Woodbury updates, the modal
assurance criterion, input checks and BLAS thread limits.  Imports nothing else of hawt."""
