"""Features: measures over an object model, and the predicates that decide propositions.

``registry`` holds the :class:`~tactile_kb.features.registry.Feature` type and the plugin
registry (entry-point group ``tactile_kb.features``); ``measures`` computes values (angles,
parallelism tables, sections, sides); ``builtin`` declares the built-in predicates.
"""
