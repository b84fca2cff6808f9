"""A small but complete field day, built through the services the way FTT records one."""

from datetime import UTC, datetime, timedelta

from events.models import Performer, Personnel, PoseSource, Vehicle, Weather
from events.services import logs, notes, segments
from events.services.segments import GpsPosition, LocalPosition
from telemetry.models.poses import FixStatus
from telemetry.services import attachments, map_images, pose_writes
from tests.support.images import grey_png, jpeg

T0 = datetime(2026, 5, 4, 8, 0, tzinfo=UTC)


def configuration(vehicle_key="husky"):
    vehicle, _ = Vehicle.objects.get_or_create(
        key=vehicle_key,
        defaults={
            "short_description": "Husky A200",
            "long_description": "Clearpath Husky with a roll cage",
            "institution": "FKIE",
            "configuration": "lidar: ouster-os1\ncamera: front",
        },
    )
    source, _ = PoseSource.objects.get_or_create(
        key="gps", defaults={"short_description": "RTK GPS", "long_description": "u-blox F9P"}
    )
    # Not seeded: a fresh installation learns it only from an archive.
    Weather.objects.get_or_create(
        key="drizzle",
        defaults={
            "short_description": "drizzle",
            "long_description": "Light rain, the lidar still sees the ground.",
            "icon": "rain",
        },
    )
    performer, _ = Performer.objects.get_or_create(institution="Fraunhofer FKIE")
    person, _ = Personnel.objects.get_or_create(name="Jörg Müller", institution="FKIE")
    return vehicle, source, performer, person


def field_day(start=T0, *, vehicle_key="husky", close=True, event=None):
    """One shift with one leg: ITO, AUTO, ITO with poses, local poses, a map, an image, a note."""
    vehicle, source, performer, person = configuration(vehicle_key)
    at = start
    if event is None:
        event = logs.create_test_event(
            at=at,
            location="Wachtberg",
            version="1.0",
            time_zone="Europe/Berlin",
            note="ELROB rehearsal",
        )
    # One person in every role: an archive of this day lists one person, which the
    # matching tests count on; more_logging() hands the roles to different people.
    shift = logs.create_shift(
        test_event=event,
        vehicle=vehicle,
        at=at + timedelta(minutes=1),
        performer=performer,
        test_administrator=person,
        test_director=person,
        safety_officer=person,
        robot_operator=person,
        test_intent="loop",
        workspace="north meadow",
        note="battery swapped before start",
    )
    leg = logs.create_leg(
        shift=shift,
        at=at + timedelta(minutes=2),
        default_pose_source=source,
        weather_id="drizzle",
        recording="/data/bags/leg-1.mcap",
        note="wet grass",
    )
    lon, lat = 7.12796, 50.61568
    for index, mode in enumerate(("ito", "auto", "ito")):
        t = at + timedelta(minutes=3 + index * 5)
        master = segments.report_mode(
            leg,
            mode,
            at=t,
            robot_stamp=t - timedelta(milliseconds=5),
            gps=GpsPosition(lon + index * 1e-4, lat),
            local=LocalPosition(float(index), -0.5, "map"),
        ).master
        pose_writes.store_poses(
            master,
            [
                pose_writes.GpsFix(
                    longitude=lon + index * 1e-4 + k * 1e-6,
                    latitude=lat + k * 1e-6,
                    altitude=101.25,
                    horizontal_accuracy=0.02,
                    fix_status=FixStatus.GBAS if k else FixStatus.SBAS,
                    robot_stamp=t + timedelta(seconds=2 * k),
                )
                for k in range(5)
            ],
        )
        pose_writes.store_local_poses(
            master,
            [
                pose_writes.MapPose(
                    x=index + k * 0.5,
                    y=k * 0.25,
                    frame="map",
                    yaw=0.1 * k,
                    robot_stamp=t + timedelta(seconds=2 * k),
                )
                for k in range(4)
            ],
        )
    child = master.children.get()
    segments.annotate_segment(
        child, ito_reason="safety", obstacle="fence", lighting="backlit", slope="15 degrees"
    )
    note = notes.add_note(child, text="stopped at the fence", author=person)
    notes.edit_note(note, text="stopped at the fence, post 4")
    map_images.store_map(
        shift,
        png=grey_png(200),
        frame="map",
        width=8,
        height=6,
        resolution=0.5,
        origin_x=-2.0,
        origin_y=-1.5,
        origin_yaw=0.25,
        robot_stamp=at + timedelta(minutes=4),
    )
    attachments.attach_image(
        master,
        content=jpeg(90),
        description="front camera",
        robot_stamp=at + timedelta(minutes=14),
    )
    if close:
        logs.close_test_event(event, at=at + timedelta(minutes=20))
    return event


def more_logging():
    """The robot goes on after a first export: a second leg with new data, then the day ends."""
    from events.models import Shift

    shift = Shift.objects.get(end__isnull=True)
    crew = [
        Personnel.objects.get_or_create(name=name, institution=institution)[0]
        for name, institution in (("Ann Lee", "FKIE"), ("Bo Chen", ""), ("Cleo Ruiz", "TNO"))
    ]
    logs.update_shift(
        shift, test_administrator=crew[0], test_director=crew[1], safety_officer=crew[2]
    )
    at = T0 + timedelta(minutes=30)
    leg = logs.create_leg(shift=shift, at=at, weather_id="cloudy")
    for index, mode in enumerate(("auto", "ito")):
        t = at + timedelta(minutes=1 + index * 3)
        master = segments.report_mode(leg, mode, at=t, gps=GpsPosition(7.128, 50.616)).master
        pose_writes.store_poses(
            master,
            [
                pose_writes.GpsFix(longitude=7.128 + k * 1e-5, latitude=50.616, robot_stamp=t)
                for k in range(3)
            ],
        )
    logs.close_test_event(shift.test_event, at=at + timedelta(minutes=10))
