"""FE model of the whole 6-PSU device: solid guideways and proximal links condensed to
super-elements at their joint reference nodes, joints as couplings (or springs), legs condensed to
the platform attachment C_i and assembled at the rigid platform (``docs/verify.md``).

Modules: :mod:`.mesh_levels` (mesh sizes), :mod:`.parts` (solid/beam super-elements of guideway and
link), :mod:`.joints` (what each joint ties, releases or springs), :mod:`.leg_model` (one leg condensed
to C_i), :mod:`.substructure` (platform assembly and the whole-device check solve), :mod:`.loads` (load
protocol of seed 000 eq. 1 with the Hertz springs), :mod:`.device_model` (one test point, all cases),
:mod:`.results` (VTU and PNG of the deformed models). Nothing heavy runs at import.
"""
