"""Interactive viewer: camera state, free-look controller and key map."""
