"""What is on disk: stereo sequences in the KITTI odometry and ASL layouts, and pose files.

``sequence``   read and write a sequence folder (``image_0/``, ``image_1/``, ``calib.txt``,
               ``times.txt``, optional ``poses.txt`` and our ``odometry.txt``); bad input raises
               one :class:`~vo_lib.formats.sequence.SequenceError` naming the file and line
``images``, ``frame_files``, ``sequence_writer``  its parts: image files, text files, writing
``poses``      trajectory files read (KITTI, TUM, EuRoC CSV, positions: one reader) and written; one
               :class:`~vo_lib.formats.poses.TrajectoryError` naming the file and line
``kitti_raw``  KITTI raw files a sequence may carry (``oxts.txt``, ``raw_calib/``): odometry, mount
``euroc``      a stereo rig as it records, in EuRoC's ASL layout (``mav0/cam0``, ``cam1``,
               ``sensor.yaml``): undistorted and rectified with OpenCV on reading, images paired by
               timestamp; bad input raises one :class:`~vo_lib.formats.euroc.AslError`
``asl_calibration`` its ``sensor.yaml`` files and the rectification computed from them
``groundtruth`` ground truth as KITTI poses, TUM, EuRoC CSV or positions only, associated with the
               images by timestamp as evo does; :class:`~vo_lib.formats.groundtruth.GroundTruthError`

Output folders (``vo_lib.outputs``) and command-line arguments (``vo_lib.arguments``) are not
file formats and live in their own modules at the bottom of the package.

Imports nothing of the package above the shared modules (``camera``, ``geometry``, ``evaluation``).
"""
