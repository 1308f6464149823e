"""Layups: stacks of plies, each draped on the tool offset by the plies below it.

``preform.stack.plies`` turns a layup scene into one drape scene per ply; ``preform.stack.maps``
measures the stack (total thickness, fibre volume fraction, plies present, where plies wrinkle);
``preform.stack.steps`` runs the plies in a case and writes the stack's outputs. The offset
surfaces are ``preform.drape.engine.offset``'s; the scene section is
``preform.pipeline.layup_section``'s.
"""
