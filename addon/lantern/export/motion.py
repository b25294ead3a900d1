"""Motion blur: the depsgraph sampled at the shutter's sub-frames, as Cycles 3.4 does
(blender/object.cpp, BlenderSync::sync_motion): object and camera transforms at their motion steps,
and deforming meshes' vertices. Only what actually moves is sent to the core, so a scene without
motion renders exactly as with motion blur off.

Cycles' conventions followed: the shutter (Render > Motion Blur > Shutter, in frames) opens around
the frame (CENTER), from it (START) or up to it (END), scene.cycles.motion_blur_position; an
object's steps are 2^motion_steps + 1 (object_motion_steps), equally spaced over the shutter, the
middle one at the shutter's centre; obj.cycles.use_motion_blur and use_deform_motion switch them
per object (and the instancer's, for instances). An object missing at a step keeps its centre
transform there (Object::update_motion), a particle instance is hidden (hide_on_missing_motion);
one missing at the centre is not rendered. Lights do not
move (Cycles 3.4 has no light motion); Volume objects move as instances do (the core looks their
grid up at each ray's time), as Cycles 3.4 blurs them.

The Vector pass with motion blur off samples the same way, as Cycles' motion pass
(Scene::MOTION_PASS): a "shutter" of 2 frames around the frame, so the steps are the previous frame,
this one and the next; every object has 3 steps (whatever its own motion blur settings) and every
mesh its deformation, the camera its own steps (0 when its motion blur is off). The core then takes
every sample at the centre step (lt_render_settings.motion_pass): nothing blurs.
"""

import numpy as np

# Blender's frame range (MAXFRAME): sub-frames beyond it cannot be evaluated.
MAX_FRAME = 1048574
# What moves with its object's transform: geometry, particle hair on meshes, Curves and point clouds.
_MESH_TYPES = {'MESH', 'CURVE', 'SURFACE', 'FONT', 'META', 'CURVES', 'POINTCLOUD'}


def _cycles(idblock):
    return getattr(idblock, "cycles", None)


def object_motion_steps(obj, parent=None):
    """Cycles' object_motion_steps: 0 without motion blur, else 2^steps + 1 (steps 1 to 7)."""
    settings = _cycles(obj)
    if settings is None:
        return 3  # without the Cycles add-on: Cycles' defaults (on, 1 step)
    if not settings.use_motion_blur:
        return 0
    steps = max(1, settings.motion_steps)
    if parent is not None and parent != obj:
        ps = _cycles(parent)
        if ps is not None:
            if not ps.use_motion_blur:
                return 0
            steps = max(steps, ps.motion_steps)
    return min((2 << (min(steps, 7) - 1)) + 1, 129)


def _uses_deform(obj, parent=None):
    settings = _cycles(obj)
    use = settings is None or settings.use_deform_motion
    if parent is not None and parent != obj:
        ps = _cycles(parent)
        use = use and (ps is None or ps.use_deform_motion)
    return use


def relative_time(step, steps):
    """Cycles' motion_time: -1 (shutter open) to 1 (shutter closed)."""
    return 2.0 * step / (steps - 1) - 1.0


def _shutter_curve_flat(rd):
    """Whether the shutter curve (Render > Motion Blur > Shutter Curve) is constant, as Blender's
    default: Lantern opens the shutter uniformly."""
    try:
        curve = rd.motion_blur_shutter_curve
        curve.initialize()
        values = [curve.evaluate(curve.curves[0], x / 16.0) for x in range(17)]
    except (AttributeError, IndexError, RuntimeError):
        return True
    return max(values) - min(values) <= 1e-4 * max(1.0, abs(max(values)))


def own_geometry(inst):
    """Whether a depsgraph instance is its object's own evaluated geometry: an object's, or the
    mesh a curve, surface, text or metaball object evaluates to (an instance whose object's
    original is its instancer), which deforms as Cycles deforms it; not an instance of another
    object (particles, collections, geometry nodes), whose geometry is shared."""
    return not inst.is_instance or (inst.parent is not None and inst.object.original == inst.parent.original)


def instance_key(inst):
    """Identifies an object instance across depsgraph evaluations (the shutter's sub-frames,
    viewport updates)."""
    if inst.is_instance:
        return (inst.object.original.as_pointer(), inst.parent.original.as_pointer(), tuple(inst.persistent_id))
    return (inst.object.original.as_pointer(),)


def _vertices(obj):
    mesh = obj.data
    if mesh is None or not hasattr(mesh, "vertices"):
        return None
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    return co


class Motion:
    """What moves over the shutter, sampled by collect(); the exporters ask transforms() and
    deformation() at the shutter's centre."""

    def __init__(self, report):
        self.report = report
        self.steps = {}        # instance key -> motion steps
        self.matrices = {}     # instance key -> {step: 4x4 float32}
        self.deform = {}       # object pointer -> motion steps (deform motion enabled, a mesh)
        self.centre_co = {}    # object pointer -> vertex positions at the centre
        self.positions = {}    # object pointer -> {step: arrays of mesh_arrays} (only when they move)
        self.camera_steps = 0
        self.camera_matrices = {}
        self.camera_fov = {}  # step -> tan(fov / 2) of a perspective camera, at the first and last steps
        self.zoom = None      # camera_zoom()'s answer
        self.moving_instances = self.deforming_meshes = 0
        # Particle instances (Cycles' hide_on_missing_motion): hidden when missing at a step.
        self.particles = set()  # their instance keys
        self.hidden_particles = 0
        self.camera_moves = False
        self.vector_pass = False  # the steps are the neighbouring frames, for the Vector pass
        # Strands and points (particle hair, Curves, point clouds) that may deform.
        self.strands = {}      # object pointer -> (name, motion steps)
        self.strand_steps = {}  # object pointer -> {step: their (n, 4) keys}

    # transforms() of a particle instance missing at some motion step: not rendered.
    HIDDEN = "hidden"

    def transforms(self, key, centre, name):
        """The instance's transforms at its motion steps, None when it does not move, or HIDDEN."""
        steps = self.steps.get(key, 0)
        mats = self.matrices.get(key)
        if steps < 3 or not mats:
            return None
        centre = np.asarray(centre, dtype=np.float32)
        out = []
        missing = False
        for s in range(steps):
            m = mats.get(s)
            if m is None and s != steps // 2:
                missing = True
            out.append(centre if m is None else m)
        if missing and key in self.particles:
            # Cycles' Object::update_motion: a particle that is born or dies within the shutter is
            # hidden (its instance has no transform there).
            self.hidden_particles += 1
            return self.HIDDEN
        if missing:
            self.report({'WARNING'}, "Object '%s' does not exist at every motion step: its transform at the "
                                     "shutter's centre is used where it is missing (as Cycles)" % name)
        if all(np.array_equal(m, centre) for m in out):
            return None
        self.moving_instances += 1
        return np.stack(out)

    def deformation(self, obj, centre_arrays):
        """(motion_positions, motion_corner_normals or None) of a deforming object, or None."""
        ptr = obj.original.as_pointer()
        steps = self.deform.get(ptr, 0)
        at = self.positions.get(ptr)
        if steps < 3 or not at:
            return None
        tris = centre_arrays["triangles"]
        positions, normals = [], []
        for s in range(steps):
            # A step not recorded had the centre's vertices.
            a = at.get(s, centre_arrays)
            if a["positions"].shape != centre_arrays["positions"].shape or \
                    not np.array_equal(a["triangles"], tris):
                self.report({'WARNING'}, "Object '%s': its mesh's topology changes over the shutter; "
                                         "deformation motion blur is off for it (its transform still "
                                         "moves), as Cycles" % obj.name)
                return None
            positions.append(a["positions"])
            normals.append(a["corner_normals"])
        self.deforming_meshes += 1
        has_normals = centre_arrays["corner_normals"] is not None and all(n is not None for n in normals)
        return np.concatenate(positions), (np.concatenate(normals) if has_normals else None)

    def strand_deformation(self, obj, centre):
        """The (steps, n, 4) keys over the shutter of obj's strands or points whose keys at the
        centre are `centre`, or None when they keep their shape (or change their count: then,
        as Cycles, no deformation blur, reported)."""
        ptr = obj.original.as_pointer()
        entry, at = self.strands.get(ptr), self.strand_steps.get(ptr)
        if entry is None or not at:
            return None
        name, steps = entry
        out = [at.get(s, centre) for s in range(steps)]  # a step not recorded had the centre's
        if any(a is None or a.shape != centre.shape for a in out):
            self.report({'WARNING'}, "Object '%s': its hair, curves or points change in number over the "
                                     "shutter; deformation motion blur is off for them (their transform "
                                     "still moves), as Cycles" % name)
            return None
        if all(np.array_equal(a, centre) for a in out):
            return None
        self.deforming_meshes += 1
        return np.stack(out)

    def camera_zoom(self, centre_fov):
        """(zoom_pre, zoom_post) of a perspective camera whose tan(fov / 2) is centre_fov at the
        shutter's centre, or None when it keeps its field of view (Cycles' perspective motion)."""
        if self.camera_steps < 3 or not self.camera_fov:
            return None
        zoom = tuple(self.camera_fov.get(s, centre_fov) / centre_fov for s in (0, self.camera_steps - 1))
        if zoom == (1.0, 1.0):
            return None
        self.camera_moves = True
        self.zoom = zoom
        return zoom

    def camera(self, centre):
        if self.camera_steps < 3 or not self.camera_matrices:
            return None
        centre = np.asarray(centre, dtype=np.float32)
        out = [self.camera_matrices.get(s, centre) for s in range(self.camera_steps)]
        if all(np.array_equal(m, centre) for m in out):
            return None
        self.camera_moves = True
        return np.stack(out)


def _sample(depsgraph, motion, rel, camera_object, mesh_arrays):
    """Records, at relative time rel, the matrices and vertices of what has a step there."""
    for inst in depsgraph.object_instances:
        if not (inst.show_self or inst.show_particles):  # an emitter hidden from render keeps its hair
            continue
        obj = inst.object
        key = instance_key(inst)
        steps = motion.steps.get(key, 0)
        if steps >= 3:
            s = round((rel + 1.0) * 0.5 * (steps - 1))
            if abs(relative_time(s, steps) - rel) < 1e-6:
                motion.matrices.setdefault(key, {})[s] = np.array(inst.matrix_world, dtype=np.float32)
        if not own_geometry(inst):
            continue
        ptr = obj.original.as_pointer()
        if ptr in motion.strands and steps >= 3:
            s = round((rel + 1.0) * 0.5 * (steps - 1))
            if abs(relative_time(s, steps) - rel) < 1e-6:
                motion.strand_steps.setdefault(ptr, {})[s] = _strand_arrays(obj)
        dsteps = motion.deform.get(ptr, 0)
        if dsteps >= 3:
            s = round((rel + 1.0) * 0.5 * (dsteps - 1))
            if abs(relative_time(s, dsteps) - rel) < 1e-6:
                co = _vertices(obj)
                centre = motion.centre_co.get(ptr)
                if co is not None and (centre is None or not np.array_equal(co, centre)):
                    arrays = mesh_arrays(obj.data)
                    if arrays is not None:
                        motion.positions.setdefault(ptr, {})[s] = arrays
    if camera_object is not None and motion.camera_steps >= 3:
        s = round((rel + 1.0) * 0.5 * (motion.camera_steps - 1))
        if abs(relative_time(s, motion.camera_steps) - rel) < 1e-6:
            cam = camera_object.evaluated_get(depsgraph)
            motion.camera_matrices[s] = np.array(cam.matrix_world, dtype=np.float32)
            if cam.type == 'CAMERA' and s in (0, motion.camera_steps - 1):
                from .camera import half_fov_tan
                motion.camera_fov[s] = half_fov_tan(cam.data, depsgraph.scene.render)


def _strand_arrays(obj):
    """Object-space strand or point arrays (x, y, z, radius) of obj: its particle hair, Curves or
    point cloud, or None."""
    from . import hair
    if obj.type == 'MESH':
        arrays = hair.particle_hair_arrays(obj, lambda *a: None) if hair.hair_systems(obj) else None
    elif obj.type == 'CURVES':
        arrays = hair.curves_arrays(obj.data)
    elif obj.type == 'POINTCLOUD':
        arrays = (hair.pointcloud_arrays(obj.data),)
    else:
        return None
    return None if arrays is None or arrays[0] is None else arrays[0]


def collect(engine, depsgraph, camera_object, report, vector_pass=False):
    """Samples the shutter's sub-frames (RenderEngine.frame_set) when the scene asks for motion
    blur, or the neighbouring frames for the Vector pass (vector_pass, without motion blur);
    leaves the depsgraph at the shutter's centre. Returns (Motion or None, restore): call
    restore() once the scene is exported to return to the frame being rendered."""
    from .mesh import mesh_arrays
    scene = depsgraph.scene
    rd = scene.render
    frame, subframe = scene.frame_current, scene.frame_subframe

    def restore():
        engine.frame_set(frame, subframe)

    settings = _cycles(scene)
    frames = not (rd.use_motion_blur and getattr(depsgraph.view_layer, "use_motion_blur", True))
    if frames and not vector_pass:
        return None, lambda: None
    # Cycles' motion_shutter_time: 2 frames around the frame for the Vector pass.
    shutter = 2.0 if frames else float(rd.motion_blur_shutter)
    if not shutter > 0:
        return None, lambda: None  # a closed shutter: nothing blurs (Cycles' shutter 0)
    position = 'CENTER' if frames else getattr(settings, "motion_blur_position", 'CENTER')
    if not frames and getattr(settings, "rolling_shutter_type", 'NONE') != 'NONE':
        report({'WARNING'}, "Rolling shutter is not supported by Lantern: the whole frame is exposed "
                            "over the same shutter interval")
    if not frames and not _shutter_curve_flat(rd):
        report({'WARNING'}, "The shutter curve is not supported by Lantern: the shutter opens and "
                            "closes instantly (Blender's default flat curve)")
    delta = {'START': 0.5 * shutter, 'END': -0.5 * shutter}.get(position, 0.0)
    centre_time = frame + subframe + delta
    if abs(centre_time) + 0.5 * shutter > MAX_FRAME:
        report({'WARNING'}, ("The Vector pass stays zero" if frames else "Motion blur off") +
               ": the shutter of %g frames reaches beyond Blender's frame range (+-%d)" % (shutter, MAX_FRAME))
        return None, lambda: None

    def go(time):
        f = int(np.floor(time))
        engine.frame_set(f, time - f)

    motion = Motion(report)
    motion.vector_pass = frames
    if delta != 0.0:
        go(centre_time)
    camera = camera_object or scene.camera
    if camera is not None:
        motion.camera_steps = object_motion_steps(camera, camera)
        if frames:  # its first and last steps are the neighbouring frames whatever their count
            motion.camera_steps = min(motion.camera_steps, 3)
    times = set()
    for inst in depsgraph.object_instances:
        volume = inst.object.type == 'VOLUME' and not frames  # blurred; no Vector pass from media
        if not (inst.show_self or inst.show_particles) or (inst.object.type not in _MESH_TYPES and not volume):
            continue
        obj = inst.object
        parent = inst.parent if inst.is_instance else None
        steps = 3 if frames else object_motion_steps(obj.original, parent.original if parent is not None else None)
        if steps < 3:
            continue
        motion.steps[instance_key(inst)] = steps
        if inst.is_instance and inst.particle_system is not None:
            motion.particles.add(instance_key(inst))
        times.update(relative_time(s, steps) for s in range(steps))
        if own_geometry(inst) and obj.type == 'MESH' and (frames or _uses_deform(obj.original)):
            co = _vertices(obj)
            if co is not None:
                motion.deform[obj.original.as_pointer()] = steps
                motion.centre_co[obj.original.as_pointer()] = co
        if not inst.is_instance and not frames and _uses_deform(obj.original) and \
                (obj.type in ('CURVES', 'POINTCLOUD') or (inst.show_particles and obj.type == 'MESH')):
            motion.strands[obj.original.as_pointer()] = (obj.name, steps)
    if motion.camera_steps >= 3:
        times.update(relative_time(s, motion.camera_steps) for s in range(motion.camera_steps))
    times.discard(0.0)
    if not times:
        if delta != 0.0:
            return motion, restore
        return motion, lambda: None
    try:
        for rel in sorted(times):
            go(centre_time + rel * 0.5 * shutter)
            _sample(depsgraph, motion, rel, camera, mesh_arrays)
    finally:
        go(centre_time)
    return motion, restore
