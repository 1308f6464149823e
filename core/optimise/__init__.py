"""The optimisation on top of the drape engine (``preform.drape``): the search over the
generators for the pattern of least shear strain energy (angle, orientation, start point),
curved generators, net relaxation, and their pipeline steps. The engine never imports this
package; its drape step takes the search's ``optimum`` product by name."""
