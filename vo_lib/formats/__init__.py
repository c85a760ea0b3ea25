"""What is on disk: stereo sequences in the KITTI odometry layout and pose files.

``sequence``   read and write a sequence folder (``image_0/``, ``image_1/``, ``calib.txt``,
               ``times.txt``, optional ``poses.txt`` and our ``odometry.txt``); bad input raises
               one :class:`~vo_lib.formats.sequence.SequenceError` naming the file and line
``poses``      KITTI and TUM trajectory files, read and written

Imports nothing of the package above the shared modules (``camera``, ``geometry``, ``evaluation``).
"""
