"""Camera export: Blender's camera parameters as they are; the core does the camera maths."""

import numpy as np

from .. import core

_SENSOR_FIT = {
    'AUTO': core.SENSOR_AUTO,
    'HORIZONTAL': core.SENSOR_HORIZONTAL,
    'VERTICAL': core.SENSOR_VERTICAL,
}


def export_camera(depsgraph, core_scene, report, camera_object=None, matrix=None, shift_x=None):
    """Sets the render camera (camera_object, else the scene's); returns its name. matrix and
    shift_x, when given, replace the object's (a stereo or multiview view's, from
    RenderEngine.camera_model_matrix and camera_shift_x)."""
    scene = depsgraph.scene
    obj = camera_object or scene.camera
    if obj is None:
        raise core.LanternError("The scene has no camera: add one and set it as the scene's "
                                "active camera (Scene Properties > Camera)")
    obj = obj.evaluated_get(depsgraph)
    rd = scene.render
    kw = dict(
        transform=np.array(obj.matrix_world if matrix is None else matrix, dtype=np.float32),
        pixel_aspect=rd.pixel_aspect_y / rd.pixel_aspect_x,
    )
    if obj.type != 'CAMERA':
        # Blender allows any object as the scene camera: render with a default camera's lens.
        report({'WARNING'}, "Scene camera '%s' is not a camera object: using a default "
                            "50 mm perspective lens at its transform" % obj.name)
        core_scene.set_camera(**kw)
        return obj.name

    cam = obj.data
    if cam.type == 'ORTHO':
        kw["type"] = core.CAMERA_ORTHOGRAPHIC
    else:
        if cam.type == 'PANO':
            report({'WARNING'}, "Camera '%s': panoramic cameras are not supported, rendered as "
                                "perspective" % obj.name)
        kw["type"] = core.CAMERA_PERSPECTIVE
    if cam.dof.use_dof:
        report({'WARNING'}, "Camera '%s': depth of field is not supported yet and is ignored"
                            % obj.name)
    kw.update(
        focal_length=cam.lens,
        sensor_width=cam.sensor_width,
        sensor_height=cam.sensor_height,
        sensor_fit=_SENSOR_FIT.get(cam.sensor_fit, core.SENSOR_AUTO),
        ortho_scale=cam.ortho_scale,
        shift_x=cam.shift_x if shift_x is None else shift_x,
        shift_y=cam.shift_y,
        clip_start=cam.clip_start,
        clip_end=cam.clip_end,
    )
    core_scene.set_camera(**kw)
    return obj.name


def camera_table(depsgraph, camera_object=None):
    """What Texture Coordinate's Camera and Window outputs need (28 floats: world to Cycles'
    camera space (+Z forward) as 3 rows of 4, then world to NDC as 4 rows of 4), or None without
    a camera object."""
    scene = depsgraph.scene
    obj = camera_object or scene.camera
    if obj is None or obj.type != 'CAMERA':
        return None
    import mathutils
    obj = obj.evaluated_get(depsgraph)
    view = obj.matrix_world.inverted()
    to_camera = mathutils.Matrix.Scale(-1.0, 4, (0.0, 0.0, 1.0)) @ view
    rd = scene.render
    x = rd.resolution_x * rd.pixel_aspect_x
    y = rd.resolution_y * rd.pixel_aspect_y
    projection = obj.calc_matrix_camera(depsgraph, x=max(1, int(x)), y=max(1, int(y)))
    ndc = mathutils.Matrix(((0.5, 0, 0, 0.5), (0, 0.5, 0, 0.5), (0, 0, 1, 0), (0, 0, 0, 1)))
    window = ndc @ projection @ view
    return [to_camera[r][k] for r in range(3) for k in range(4)] + \
        [window[r][k] for r in range(4) for k in range(4)]
