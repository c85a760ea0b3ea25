"""What is on disk: stereo sequences in the KITTI odometry layout and pose files.

``sequence``   read and write a sequence folder (``image_0/``, ``image_1/``, ``calib.txt``,
               ``times.txt``, optional ``poses.txt`` and our ``odometry.txt``); bad input raises
               one :class:`~vo_lib.formats.sequence.SequenceError` naming the file and line
``poses``      KITTI and TUM trajectory files, read and written; bad input raises one
               :class:`~vo_lib.formats.poses.TrajectoryError` naming the file and line
``kitti_raw``  KITTI raw files a sequence may carry (``oxts.txt``, ``raw_calib/``): odometry, mount

Output folders (``vo_lib.outputs``) and command-line arguments (``vo_lib.arguments``) are not
file formats and live in their own modules at the bottom of the package.

Imports nothing of the package above the shared modules (``camera``, ``geometry``, ``evaluation``).
"""
