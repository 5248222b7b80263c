"""Forward-difference span engine (seeds 000, 001): not built yet; see the quadratic-shading issue."""
