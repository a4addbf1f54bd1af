//! Clip sampling: a clip and a time to local joint transforms.
