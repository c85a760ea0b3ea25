"""What is on disk: stereo sequences in the KITTI odometry layout and pose files.

``sequence``   read and write a sequence folder (``image_0/``, ``image_1/``, ``calib.txt``,
               ``times.txt``, optional ``poses.txt`` and our ``odometry.txt``); bad input raises
               one :class:`~vo_lib.formats.sequence.SequenceError` naming the file and line
``poses``      KITTI and TUM trajectory files, read and written; bad input raises one
               :class:`~vo_lib.formats.poses.TrajectoryError` naming the file and line
``outputs``    output folders written whole or not at all, never over what this package did not
               write (a marker file tells), temporary folders cleaned up
``kitti_raw``  KITTI raw recordings: GPS/IMU packets (``oxts.txt``), the camera's place in the car
``arguments``  command-line parsing shared by the entry points: one-line errors, exit status 2

Imports nothing of the package above the shared modules (``camera``, ``geometry``, ``evaluation``).
"""
