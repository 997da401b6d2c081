"""Compares packs dataset by dataset, bit for bit, leaving out the wall-clock bake timings
(datasets named *_s in a 'bake' group). Prints one line per pack and exits 1 on any difference.
    compare_packs.py PACK PACK [PACK ...]
Needs h5py (Debian's python3-h5py; tools/setup.sh installs it)."""
import hashlib
import sys

import h5py


def timing(name):
    parts = name.split("/")
    return len(parts) >= 2 and parts[-2] == "bake" and parts[-1].endswith("_s")


def digest(path):
    """sha256 over every dataset's and attribute's name, type, shape and bytes, timings aside."""
    h = hashlib.sha256()

    def attrs(name, obj):
        for key in sorted(obj.attrs.keys()):
            value = obj.attrs[key]
            h.update(f"{name}@{key}={value!r}".encode())

    with h5py.File(path, "r") as f:
        attrs("/", f)
        names = []
        f.visit(names.append)
        for name in sorted(names):
            obj = f[name]
            attrs(name, obj)
            if isinstance(obj, h5py.Dataset) and not timing(name):
                data = obj[()]
                h.update(f"{name}:{obj.dtype}:{obj.shape}".encode())
                h.update(data.tobytes() if hasattr(data, "tobytes") else repr(data).encode())
    return h.hexdigest()


def main():
    digests = [digest(p) for p in sys.argv[1:]]
    for p, d in zip(sys.argv[1:], digests):
        print(f"{d[:16]}  {p}")
    return 0 if len(set(digests)) == 1 else 1


if __name__ == "__main__":
    sys.exit(main())
