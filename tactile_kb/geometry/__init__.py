"""Geometry: contacts → planes → polyhedron → object model.

``planes`` merges contact planes into faces and fits them; ``polyhedron`` intersects the
half-spaces; ``sections`` cuts layer contours; ``blocks`` stacks them into a box-union solid;
``model`` assembles the :class:`~tactile_kb.geometry.model.ObjectModel`.
"""
