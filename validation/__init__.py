"""The validation suite: published measured shear curves, and the model compared with them.

Installed as ``preform.validation_suite`` (the repository's top-level ``validation/`` folder);
``preform validate`` runs it. Each dataset is a folder of ``datasets/`` holding ``dataset.yaml``
(citation, specimen, how the points were digitised, their uncertainty, licence) and the points.
"""
