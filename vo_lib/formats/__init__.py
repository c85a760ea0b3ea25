"""What is on disk: stereo sequences (KITTI and ASL layouts), pose and ground-truth files;
the package map of docs/layout.md says which module reads what."""
