"""Camera export: Blender's camera parameters as they are; the core does the camera maths."""

import numpy as np

from .. import core

_SENSOR_FIT = {
    'AUTO': core.SENSOR_AUTO,
    'HORIZONTAL': core.SENSOR_HORIZONTAL,
    'VERTICAL': core.SENSOR_VERTICAL,
}
# Cycles 3.4's panoramic projections that Lantern renders (cam.cycles.panorama_type).
_PANORAMA = {
    'EQUIRECTANGULAR': core.PANORAMA_EQUIRECTANGULAR,
    'FISHEYE_EQUIDISTANT': core.PANORAMA_FISHEYE_EQUIDISTANT,
    'FISHEYE_EQUISOLID': core.PANORAMA_FISHEYE_EQUISOLID,
    'MIRRORBALL': core.PANORAMA_MIRRORBALL,
    'FISHEYE_LENS_POLYNOMIAL': core.PANORAMA_FISHEYE_LENS_POLYNOMIAL,
    'EQUIANGULAR_CUBEMAP_FACE': core.PANORAMA_EQUIANGULAR_CUBEMAP_FACE,
}


def focus_distance(depsgraph, camera_object, matrix=None):
    """Cycles' focus distance (blender_camera_focal_distance): dof.focus_distance, or with a focus
    object (or its bone, focus_subtarget) the distance between it and the camera along the
    camera's view axis, taken absolute as Cycles does (an object behind the camera focuses at the
    same distance in front)."""
    import mathutils
    cam = camera_object.data
    target = cam.dof.focus_object
    if target is None:
        return cam.dof.focus_distance
    target = target.evaluated_get(depsgraph)
    target_matrix = target.matrix_world
    bone = cam.dof.focus_subtarget
    if bone and target.pose and bone in target.pose.bones:
        target_matrix = target_matrix @ target.pose.bones[bone].matrix
    m = mathutils.Matrix(camera_object.matrix_world if matrix is None else matrix)
    view_axis = m.col[2].to_3d().normalized()
    return abs(view_axis.dot(m.col[3].to_3d() - target_matrix.col[3].to_3d()))


def export_camera(depsgraph, core_scene, report, camera_object=None, matrix=None, shift_x=None, motion=None):
    """Sets the render camera (camera_object, else the scene's); returns its name. matrix and
    shift_x, when given, replace the object's (a stereo or multiview view's, from
    RenderEngine.camera_model_matrix and camera_shift_x). motion: export/motion.py's Motion (the
    camera's transforms over the shutter), or None."""
    scene = depsgraph.scene
    obj = camera_object or scene.camera
    if obj is None:
        raise core.LanternError("The scene has no camera: add one and set it as the scene's "
                                "active camera (Scene Properties > Camera)")
    core_scene.set_camera(**camera_keywords(depsgraph, obj, report, matrix, shift_x, motion))
    return obj.name


def camera_keywords(depsgraph, obj, report, matrix=None, shift_x=None, motion=None):
    """core.Scene.set_camera's keywords for camera object obj (export_camera's arguments)."""
    scene = depsgraph.scene
    obj = obj.evaluated_get(depsgraph)
    rd = scene.render
    kw = dict(
        transform=np.array(obj.matrix_world if matrix is None else matrix, dtype=np.float32),
        pixel_aspect=rd.pixel_aspect_y / rd.pixel_aspect_x,
    )
    if motion is not None and matrix is None:
        kw["motion"] = motion.camera(kw["transform"])
    if obj.type != 'CAMERA':
        # Blender allows any object as the scene camera: render with a default camera's lens.
        report({'WARNING'}, "Scene camera '%s' is not a camera object: using a default "
                            "50 mm perspective lens at its transform" % obj.name)
        return kw

    cam = obj.data
    kw["type"] = core.CAMERA_PERSPECTIVE
    if cam.type == 'ORTHO':
        kw["type"] = core.CAMERA_ORTHOGRAPHIC
    elif cam.type == 'PANO':
        kw.update(_panorama(cam, obj.name, report))
    if kw["type"] == core.CAMERA_PERSPECTIVE and motion is not None and matrix is None:
        kw["zoom"] = motion.camera_zoom(half_fov_tan(cam, rd))
    dof = cam.dof
    if dof.use_dof:
        distance = focus_distance(depsgraph, obj, matrix)
        if distance > 0:
            kw.update(use_dof=True, focus_distance=distance, aperture_fstop=dof.aperture_fstop,
                      aperture_blades=dof.aperture_blades, aperture_rotation=dof.aperture_rotation,
                      aperture_ratio=dof.aperture_ratio)
        else:
            report({'WARNING'}, "Camera '%s': the focus distance is 0 (the plane in focus at the "
                                "lens), depth of field is ignored" % obj.name)
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
    return kw


def _panorama(cam, name, report):
    """set_camera keywords for a panoramic camera: Cycles' panorama settings, which Blender 3.4
    keeps in the Cycles add-on's camera properties (cam.cycles)."""
    ccam = getattr(cam, "cycles", None)
    if ccam is None or not hasattr(ccam, "panorama_type"):
        report({'WARNING'}, "Camera '%s': a panoramic camera's settings are the Cycles add-on's; "
                            "enable Cycles (Preferences > Add-ons) to render them. Rendered as "
                            "perspective" % name)
        return {}
    if ccam.panorama_type not in _PANORAMA:
        report({'WARNING'}, "Camera '%s': panorama type %s is not supported by Lantern (it "
                            "renders %s); rendered as perspective"
                            % (name, ccam.panorama_type, ", ".join(sorted(_PANORAMA))))
        return {}
    return dict(type=core.CAMERA_PANORAMA, panorama_type=_PANORAMA[ccam.panorama_type],
                fisheye_fov=ccam.fisheye_fov, fisheye_lens=ccam.fisheye_lens,
                latitude_min=ccam.latitude_min, latitude_max=ccam.latitude_max,
                longitude_min=ccam.longitude_min, longitude_max=ccam.longitude_max,
                fisheye_polynomial=[getattr(ccam, "fisheye_polynomial_k%d" % i) for i in range(5)])


def half_fov_tan(cam, rd):
    """tan of half a perspective camera's field of view as Cycles takes it for its perspective motion
    (blender/camera.cpp: 0.5 sensor size / lens / aspect ratio, the sensor fitted to the frame)."""
    x, y = rd.resolution_x * rd.pixel_aspect_x, rd.resolution_y * rd.pixel_aspect_y
    horizontal = cam.sensor_fit == 'HORIZONTAL' or (cam.sensor_fit == 'AUTO' and x > y)
    size = cam.sensor_height if cam.sensor_fit == 'VERTICAL' else cam.sensor_width
    return 0.5 * size / cam.lens / (x / y if horizontal else y / x)


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
