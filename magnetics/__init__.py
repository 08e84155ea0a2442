"""Magnetics of the MR drum clutch: materials, a saturating circuit, an axisymmetric FEM
(scikit-fem, imported inside its functions), yield and viscous torque.

Imports run geometry ← magnetics: this package reads a clutch only through its section
(``geometry.section``) or, for arrays of designs, ``geometry.batch.layout``.
"""
