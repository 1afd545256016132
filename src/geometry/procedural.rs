//! Procedural scenes built in code: corner, cube with a hole, supershape, sphere, plane.
