import sys

from lerobot_contrast.sweep.command import main

sys.exit(main())
