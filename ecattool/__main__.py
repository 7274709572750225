import sys

from ecattool._entry import main

sys.exit(main())
