"""Time records in (issue 33): recordings of a stepped-sine test -> a sweep file.

- :mod:`.record`: the common :class:`TimeRecord` (named channels, sample rate, start time, path);
- :mod:`.readers`: MATLAB v5/v7.3, TDMS, WAV, CSV, Parquet (pyarrow optional), UFF58 type 1, HDF5;
- :mod:`.channel_map`: the channel map YAML (force/current, probes, keyphasor, step table, settings);
- :mod:`.steps`, :mod:`.keyphasor`, :mod:`.periodfit`, :mod:`.analysis`: the stepped-sine analysis;
- :mod:`.ingest`: files in, sweep file out (atomic, with provenance).

Layer: beside :mod:`rotorcheck.sweep` (it writes sweeps; it does not know the simulator).
"""

from rotorcheck.ingest.analysis import IngestResult, analyse
from rotorcheck.ingest.channel_map import ChannelMap, load_channel_map, parse_channel_map
from rotorcheck.ingest.ingest import ingest_files, read_records
from rotorcheck.ingest.readers import open_record, parquet_available
from rotorcheck.ingest.record import TimeRecord, concatenate

__all__ = ["ChannelMap", "IngestResult", "TimeRecord", "analyse", "concatenate", "ingest_files", "load_channel_map",
           "open_record", "parquet_available", "parse_channel_map", "read_records"]
