"""Opcode numbers of the core's shader machine, as native/src/shading/*.h declare them (a test
holds the two to each other)."""

# shaders.h
EMISSION = 1
DIFFUSE = 2
GLOSSY = 3
GLASS = 4
TRANSPARENT = 5
PRINCIPLED = 6
MIX_WEIGHTS = 7
HOLDOUT = 8

# inputs.h
TEX_COORD = 32
GEOMETRY = 33
IMAGE = 34
FRESNEL = 35
LAYER_WEIGHT = 36
LIGHT_PATH = 37
TO_FLOAT = 38
TO_VECTOR = 39

# Distribution params (shaders.h)
DIST_SHARP = 0
DIST_GGX = 1
DIST_BECKMANN = 2
DIST_ASHIKHMIN_SHIRLEY = 3
DIST_MULTI_GGX = 4
