"""The preform's properties read from a drape: thickness, fibre volume fraction, permeability."""
