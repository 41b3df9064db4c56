"""The planar model: the pipe's residual and Jacobians in the plane (Eq. (20)), its terms and variants."""
