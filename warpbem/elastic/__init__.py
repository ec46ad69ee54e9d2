"""Interior linear elasticity of cells (thesis ch. 2.2 C): the displacement of a cell from its
surface traction by the elastic boundary integral equation."""
