"""Blender's generic attributes (Mesh, Curves and PointCloud .attributes) read as arrays."""

import numpy as np

# Attribute data types: (property, components, numpy type). 'color' is scene linear for byte and
# float colours alike (Cycles reads them linear).
_TYPES = {
    'FLOAT': ("value", 1, np.float32), 'INT': ("value", 1, np.int32), 'BOOLEAN': ("value", 1, bool),
    'FLOAT2': ("vector", 2, np.float32), 'FLOAT_VECTOR': ("vector", 3, np.float32),
    'FLOAT_COLOR': ("color", 4, np.float32), 'BYTE_COLOR': ("color", 4, np.float32),
}


def attribute_array(attr):
    """(components, values (len(attr.data), components) float32) of an attribute, or None for a
    data type Cycles does not read."""
    kind = _TYPES.get(attr.data_type)
    if kind is None:
        return None
    prop, n, dtype = kind
    values = np.empty(len(attr.data) * n, dtype=dtype)
    attr.data.foreach_get(prop, values)
    return n, values.astype(np.float32).reshape(-1, n)
