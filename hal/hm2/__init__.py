"""Mesa HostMot2 boards over Ethernet: LinuxCNC's hostmot2 and hm2_eth, and a simulated board.

- ``lbp16``: the LBP16 protocol (commands in UDP datagrams, port 27181);
- ``idrom``: how a HostMot2 firmware describes itself (IDROM, module and pin descriptors);
- ``firmware``: board layouts (the 7I96S's stock firmware);
- ``sim``: a simulated board answering LBP16 (``python -m hal.hm2.sim``);
- ``eth``: the host's side of the link: packets, packet numbers, read timeouts, errors;
- ``driver`` and ``functions``: the hostmot2 driver: discovery, configuration, the HAL
  pins of each function and what ``read``/``write`` do each period.

The HAL components are ``hal/components/hostmot2.py`` and ``hm2_eth.py``.
"""
