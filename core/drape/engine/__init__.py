"""The drape engine: tools, the ply, the pin-jointed net and its generators, the part, the net's
cell fields and the result they make (``docs/design.md``: the drape's rooms)."""
