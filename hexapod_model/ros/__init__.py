"""ROS 2 without a ROS installation: the service's records as ROS 2 topics over DDS, and MCAP bags.

* :class:`~hexapod_model.ros.dds.RosBridge`: publishes a running
  :class:`~hexapod_model.service.FixtureService`'s records (``[ros]`` in ``fixture.toml``) with
  Eclipse Cyclone DDS's Python binding under ROS 2's names, types and QoS, so that ROS 2 nodes
  (``rclpy``, ``rclcpp``, RViz, Foxglove) receive them.
* :class:`~hexapod_model.ros.changeover_topics.ChangeoverTopics` (run by the bridge): each
  fixture's guidance as a topic, and targets set over ROS 2 by messages signed with the
  service's token (:func:`~hexapod_model.ros.changeover_topics.request`).
* :func:`~hexapod_model.ros.redundancy.consistency_values`: a fixture with redundant sensors
  carries its consistency test on ``/diagnostics`` (live and in the bag).
* :func:`~hexapod_model.ros.bag.write_mcap`: the store's sample log and lock events as a ROS 2
  bag in MCAP (``hexapod fixture history CONFIG --mcap out.mcap``).

Needs the ``ros`` extra (``pip install 'hexapod_model[ros]'``: cyclonedds, rosbags, mcap); this
package imports none of it until used. Topics, frames, QoS and discovery: ``docs/ros2.md``.
"""
