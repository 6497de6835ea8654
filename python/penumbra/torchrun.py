"""`python3 -m penumbra.torchrun ARGS` runs `torchrun ARGS` (torch.distributed.run), repaired for Debian 12.

Debian 12's torch 1.13 launcher parses --redirects / --tee by iterating the IntFlag `Std`, which under Python 3.11
skips NONE and ALL, so every `torchrun` invocation fails with "'NoneType' object has no attribute 'get'". This
module parses those two options with Std(int) when the installed launcher has that defect, then runs the
launcher unchanged (all of torchrun's options, single- and multi-node).
"""
import re
import sys

from torch.distributed.elastic.multiprocessing import api


def _std_from_str(text):
    if re.match(api._VALUE_REGEX, text):
        return api.Std(int(text))
    if re.match(api._MAPPING_REGEX, text):
        return {int(rank): api.Std(int(value)) for rank, value in (m.split(":") for m in text.split(","))}
    raise ValueError("%s does not match %s or %s" % (text, api._VALUE_REGEX, api._MAPPING_REGEX))


def main():
    if api.Std.from_str("0") is None:
        api.Std.from_str = staticmethod(_std_from_str)
    from torch.distributed.run import main as run
    run()


if __name__ == "__main__":
    sys.exit(main())
