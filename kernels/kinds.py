"""The integrands the boundary-integral kernels are built for (``assembly.build_kernels``; each
described in that module's docstring), in a module without Warp, so the package can name them
before it loads Warp."""

KINDS = ("double_layer", "adjoint_double_layer", "single_layer", "inverse_distance", "elastic_rotation",
         "elastic_dyadic")
