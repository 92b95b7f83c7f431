"""Cross-check of the bag and MCAP readers against an independent writer (manual, not in CI).

    pip install rosbags numpy
    python3 scripts/bags_crosscheck.py   # imu.csv, imu.bag, bz2.bag, lz4.bag (ROS 1), imu2/imu2.mcap (ROS 2)
    for f in imu.csv imu.bag bz2.bag lz4.bag imu2/imu2.mcap imu2; do imudrift allan $f --json > $(basename $f).json; done

The three Allan results must agree (docs/validation.md, "Log inputs").
"""
import numpy as np
from rosbags.rosbag1 import Writer as W1
from rosbags.rosbag2 import Writer as W2, StoragePlugin
from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.stores.ros1_noetic import sensor_msgs__msg__Imu as Imu1, std_msgs__msg__Header as H1, builtin_interfaces__msg__Time as T1, geometry_msgs__msg__Quaternion as Q1, geometry_msgs__msg__Vector3 as V1
ts1 = get_typestore(Stores.ROS1_NOETIC)
ts2 = get_typestore(Stores.ROS2_HUMBLE)
rng = np.random.default_rng(3)
n = 20000
g = rng.normal(0, 1e-3, (n,3)); a = rng.normal(0, 1e-2, (n,3)); a[:,2] -= 9.80665
t0 = 1_700_000_000_000_000_000
with open('imu.csv','w') as f:
    f.write('t,gx,gy,gz,ax,ay,az\n')
    for k in range(n):
        f.write(','.join([repr(k*0.005)] + [repr(float(v)) for v in (*g[k], *a[k])]) + '\n')
def msg(ts, k, ros2):
    T = ts.types['builtin_interfaces/msg/Time']; H = ts.types['std_msgs/msg/Header']
    Q = ts.types['geometry_msgs/msg/Quaternion']; V = ts.types['geometry_msgs/msg/Vector3']; I = ts.types['sensor_msgs/msg/Imu']
    ns = t0 + k*5_000_000
    hdr = H(stamp=T(sec=ns//10**9, nanosec=ns%10**9), frame_id='imu') if ros2 else H(seq=k, stamp=T(sec=ns//10**9, nanosec=ns%10**9), frame_id='imu')
    z = np.zeros(9)
    return I(header=hdr, orientation=Q(x=0.,y=0.,z=0.,w=1.), orientation_covariance=z, angular_velocity=V(x=g[k,0],y=g[k,1],z=g[k,2]), angular_velocity_covariance=z, linear_acceleration=V(x=a[k,0],y=a[k,1],z=a[k,2]), linear_acceleration_covariance=z), ns
with W1('imu.bag') as w:
    c = w.add_connection('/imu0', 'sensor_msgs/msg/Imu', typestore=ts1)
    for k in range(n):
        m, ns = msg(ts1, k, False)
        w.write(c, ns, ts1.serialize_ros1(m, 'sensor_msgs/msg/Imu'))
with W2('imu2', version=8, storage_plugin=StoragePlugin.MCAP) as w:
    c = w.add_connection('/imu0', 'sensor_msgs/msg/Imu', typestore=ts2)
    for k in range(n):
        m, ns = msg(ts2, k, True)
        w.write(c, ns, ts2.serialize_cdr(m, 'sensor_msgs/msg/Imu'))
print('written')

# The same samples in ROS 1 bags with bz2- and lz4-compressed chunks.
for comp, name in [(W1.CompressionFormat.BZ2, 'bz2.bag'), (W1.CompressionFormat.LZ4, 'lz4.bag')]:
    w = W1(name)
    w.set_compression(comp)
    w.open()
    c = w.add_connection('/imu0', 'sensor_msgs/msg/Imu', typestore=ts1)
    for k in range(n):
        m, ns = msg(ts1, k, False)
        w.write(c, ns, ts1.serialize_ros1(m, 'sensor_msgs/msg/Imu'))
    w.close()
print('compressed bags written')
