"""Humusoft MF624 register layout and Linux device facts the ``mf624`` backend relies on, with their sources.

PCI regions. Humusoft's manual names three regions BADR0, BADR1, BADR2; on the card they are PCI BAR0, BAR2 and
BAR4 (the kernel's uio_mf624.c: "Datasheet says device uses BAR0, BAR1, BAR2 -- do not trust it"; comedi's
mf6x4.c likewise uses bar_nums {0, 2, 4} for the MF624):

=========  =======  ====================================  ===============================================
manual     PCI      contents                              uio_mf624 map (mmap offset = index * page size)
=========  =======  ====================================  ===============================================
BADR0      BAR0     PCI bridge: INTCSR 0x4C, GPIOC 0x54   map0
BADR1      BAR2     ADC, DAC (DA0..DA7 at 0x20 + 2 n),    map1
                    DIN/DOUT 0x10
BADR2      BAR4     counter/timers CTR0..CTR4 (0x10 n),   map2
                    IRCSTATUS/IRCCTRL 0x6C, IRC0..IRC3
                    0x70, 0x74, 0x78, 0x7C (32 bit)
=========  =======  ====================================  ===============================================

The IRC (incremental encoder) offsets are from Humusoft's own data acquisition library, file MF624.c
(hudaqlib, "Copyright 2006-2007 Humusoft s.r.o."): ``IRCSTATUS = 0x6C`` (read), ``IRCCTRL = 0x6C`` (write),
``IRC0..IRC3 = 0x70, 0x74, 0x78, 0x7C`` in BADR2, each a 32-bit count read with one dword access
(``GetDword(MemResources[2].Base, IRC0 + 4*channel)``). Note: offsets 0x00, 0x04, 0x08, 0x0C, 0x10 of BADR2 are
the counter/timer registers (``0x10*channel``), not the encoders, whatever other summaries say. The manual
itself could not be consulted here, so the offsets are config entries of the backend (``irc_register_offsets``,
``irc_control_offset``), defaulting to the values below.

IRCCTRL holds one byte per encoder input n (bits 8n..8n+7), per hudaqlib's ``IRC_Control`` bit field:
bits 0-1 mode (00 quadrature "IRC" mode, 01 rising edges of A, 10 falling, 11 both), bits 2-3 count control
(00 counting enabled), bits 4-6 reset mode (000 counting, 001 held at reset, others reset on index I), bit 7
input filter (1 on). IRCCTRL_QUADRATURE_COUNTING = 0 selects quadrature counting, no reset, no filter on all four.
The quadrature decoding factor (x4, every edge of A and B) is the bridge config's stated assumption
(``quadrature_counts_per_line``); the counts are passed on raw.

Memory map of the counter registers (uio_mf624.c, kernels >= 4.x: ``mf624_setup_mem``): each UIO map starts at
the page holding the BAR (``mem->addr = start & PAGE_MASK``), its size is rounded up to whole pages, and the BAR
begins ``mem->offs = start & ~PAGE_MASK`` bytes into it, published as /sys/class/uio/uioN/maps/mapM/offset
(size in .../size). The backend mmaps map M at file offset ``M * page size`` and adds that in-page offset.

A PCI function is bound to one kernel driver at a time, and comedi's mf6x4 and uio_mf624 both claim the MF624
(186c:0624). So /dev/comedi0 (mf6x4) and /dev/uioN (uio_mf624) cannot both exist for one card. With mf6x4 bound
(needed for comedi's analog and digital outputs) map the counter BAR through the PCI core instead:
``irc_device_path: /sys/bus/pci/devices/<domain:bus:dev.fn>/resource4`` (BAR4 at file offset 0; readable by root
or through a udev rule). The backend mmaps either kind of path the same way except for the offset rule above.

Comedi side (mf6x4.c): subdevice 0 AI, 1 AO (8 channels, 14 bit, maxdata 0x3FFF, one range: bipolar +-10 V),
2 DI (8), 3 DO (8). The backend finds the AO and DO subdevices by type and converts volts with comedilib's
linear law (comedi_from_phys).
"""
from __future__ import annotations

#: PCI vendor and device id of the MF624
PCI_VENDOR_ID = 0x186C
PCI_DEVICE_ID = 0x0624

#: UIO map index of BADR2 (PCI BAR4, counters and encoders) under uio_mf624
UIO_COUNTER_MAP_INDEX = 2

#: BADR2 offsets (bytes), hudaqlib MF624.c
IRC_STATUS_OFFSET = 0x6C
IRC_CONTROL_OFFSET = 0x6C
IRC_REGISTER_OFFSETS = (0x70, 0x74, 0x78, 0x7C)
#: the smallest BADR2 span that holds IRC3
COUNTER_BAR_MIN_BYTES = 0x80

#: IRCCTRL value: all four inputs in quadrature mode, counting enabled, not reset, no input filter
IRCCTRL_QUADRATURE_COUNTING = 0x00000000
IRCCTRL_FILTER_BITS = 0x80808080

#: comedi's range for the MF624 analog outputs (mf6x4.c: range_bipolar10) and its 14-bit maxdata
AO_RANGE_V = (-10.0, 10.0)
AO_MAXDATA = 0x3FFF
