//! Generic rigidity by counting: the (B, B) pebble game on the body-bar multigraph.
