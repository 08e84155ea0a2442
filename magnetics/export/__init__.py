"""Hand-off files for the solvers a designer already trusts: FEMM 4.2 (``femm``) and ONELAB,
Gmsh + GetDP (``onelab``). Each writes the same axisymmetric, non-linear magnetostatic
problem the tool's FEM solves (magnetics.fem): the section's regions with their materials'
B–H curves, the coil's ampere-turns, ψ = r·A_φ = 0 on the axis and on the same air box,
and a recipe that reads the yield torque from the field the tool's way (docs/handoff.md).
"""
