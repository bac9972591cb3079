import sys

from lerobot_contrast.view.command import main

sys.exit(main())
