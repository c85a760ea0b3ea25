"""The simulated world and its sensors: where every sample sequence and laser scan comes from.

``world``          one 2-D floor plan of line segments, extruded to textured planes (start here)
``textures``       procedural, photographic and painted textures
``render``         rectified stereo pairs of a world, with sensor effects
``composite``      the renderer's z-buffer step, compiled; ``composite_plain`` the same in NumPy
``laser``          a 2-D laser scanner ray-cast against the same segments
``trajectories``   crawler drives with slipping tracks: truth and what the encoders report
``road``           the road drive: a car's path, the road's climb and bank, the car's 6-DoF poses
``samples``        the named samples ([Zhao]'s experiments, [Yuan]'s corridor), rendered
                   to the KITTI layout of ``vo_lib.formats``
``frame_store``    rendered frames kept on disk for the next process (the test suite sets its folder)
``realism``        image statistics that compare rendered frames with real ones

The simulation uses the motion models (``vo_lib.models``) and the file formats, never an
estimator: the wings build on it, not the other way round.
"""
