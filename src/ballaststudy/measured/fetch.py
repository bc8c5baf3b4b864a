"""The public measured curves fetched from their source, each checked by its hash.

The curves that calibration and the loop compare with (Sun et al. 2016, Tennakoon and
Indraratna 2014, digitised by the authors of the repository erolsson/railway_ballast) are
not ours to ship: that repository states no licence. They are downloaded from it at a
pinned commit, file by file into measured.data_dir keeping the source's folders, and each
file's SHA-256 is checked against registry.txt, so a changed or truncated file is refused
rather than read. pooch (BSD-3-Clause, the scientific Python ecosystem's fetcher) does the
download, the check and the atomic move; a file already there with the right hash is not
downloaded again.
"""
from pathlib import Path

import pooch
import requests

from ..schema import ConfigError

SOURCE_REPOSITORY = "erolsson/railway_ballast"
SOURCE_COMMIT = "cfc86c22cc5e2f857c24ba1a01c2541edf839e3b"
SOURCE_URL = f"https://raw.githubusercontent.com/{SOURCE_REPOSITORY}/{SOURCE_COMMIT}/experimental_data/"
REGISTRY = Path(__file__).with_name("registry.txt")


def registered_files():
    """The curve files' paths (relative to measured.data_dir) in registry.txt's order."""
    return [line.split()[0] for line in REGISTRY.read_text().splitlines() if line.strip() and line[0] != "#"]


def fetch(data_dir, url=SOURCE_URL, names=None):
    """Download the registered curve files ``names`` (None: all) from ``url`` (the source at
    the pinned commit, or a mirror of its experimental_data/ folder) into ``data_dir``;
    their paths. Raises ConfigError naming the file on a failed download or a wrong hash
    (that file is not written)."""
    store = pooch.create(path=Path(data_dir), base_url=url if url.endswith("/") else url + "/", registry=None)
    store.load_registry(REGISTRY)
    paths = []
    for name in list(store.registry) if names is None else names:     # the registry's order
        if name not in store.registry:
            raise ConfigError(REGISTRY, name, "is not a registered curve file")
        try:
            paths.append(Path(store.fetch(name)))
        except ValueError as err:           # pooch: the hash differs
            raise ConfigError(store.get_url(name), None, f"refused: not the registered file ({err})") from None
        except requests.RequestException as err:
            raise ConfigError(store.get_url(name), None, f"could not be downloaded ({type(err).__name__}): "
                              "is the network up, or does the url name a mirror of the source?") from None
    return paths
